#include "qm3d/mesh/cmdm.h"

#include "multiscale.h"

namespace qm3d::mesh {
namespace {

// MEPP2 process_CMDM_multires (SPEC-CMDM 1.4-1.8): rc = 0.001, +0.0005 per scale; curvature
// radius rc BB, neighbourhood 3 rc BB, sigma a third of it; crossing-edge curvature; Heron
// distances from the projected point; ">= 0" walk test; colour; w1 covariances clamped at 0.
constexpr detail::MultiscaleDefinition kCmdm{
    "CMDM", detail::CurvatureVariant::kCmdm, 0.001, 0.0005, 3.0, 3.0,
    detail::HeronAnchor::kProjectedPoint, /*strict_outward_test=*/false, /*uses_color=*/true,
    kCmdmConventions};

}  // namespace

MeshMetricResult compute_cmdm(const ColoredMesh& reference, const ColoredMesh& distorted,
                              const CmdmOptions& options) {
  const auto table = Lab2000hlTable::shared(resolve_data_dir(options.data_dir));
  // CMDM = weights . (features averaged over vertices and scales) = mean local distortion
  // (MEPP2: sum over vertices / (n * scales), then the weights).
  const auto pool = [&](const std::vector<FeatureVector>& sums, int scales, DirectionResult& r) {
    const double count = static_cast<double>(sums.size()) * scales;
    FeatureVector total{};
    for (const auto& s : sums) {
      for (std::size_t k = 0; k < kNumFeatures; ++k) total[k] += s[k];
    }
    for (std::size_t k = 0; k < kNumFeatures; ++k) r.features[k] = total[k] / count;
    r.score = options.model.apply(r.features);
    if (!options.per_vertex) return;
    r.local_distortion.resize(sums.size());
    for (std::size_t v = 0; v < sums.size(); ++v) {
      r.local_distortion[v] = options.model.apply(sums[v]) / scales;
    }
  };
  return detail::run_multiscale(reference, distorted, kCmdm,
                                {options.direction, options.scales, table.get()}, pool);
}

}  // namespace qm3d::mesh
