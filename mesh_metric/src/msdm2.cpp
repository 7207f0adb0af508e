#include "qm3d/mesh/msdm2.h"

#include "multiscale.h"
#include "qm3d/common/pooling.h"

namespace qm3d::mesh {
namespace {

// MEPP2 process_msdm2_multires (SPEC-CMDM 2): rc = 0.002, +0.001 per scale; neighbourhood
// 5 rc BB with sigma = h / 2; generic curvature (every edge in the ball); Heron distances from
// the distorted vertex itself; "> 0" walk test; no colour; mixed-weight unclamped covariance.
constexpr detail::MultiscaleDefinition kMsdm2{
    "MSDM2", detail::CurvatureVariant::kGeneric, 0.002, 0.001, 5.0, 2.0,
    detail::HeronAnchor::kQueryPoint, /*strict_outward_test=*/true, /*uses_color=*/false,
    kMsdm2Conventions};

// Local score (f1 + f2 + 0.5 f3) / (2 + 0.5) (msdm2.h compute_statistics, param = 0.5), and
// Minkowski pooling with p = 3 (process_msdm2_multires).
const LinearModel kMsdm2Local{"msdm2", {0.4, 0.4, 0.2, 0, 0, 0, 0, 0},
                              "Lavoue 2011; MEPP2 msdm2.h: (f1 + f2 + 0.5 f3) / 2.5"};
constexpr double kMinkowskiExponent = 3.0;

}  // namespace

MeshMetricResult compute_msdm2(const ColoredMesh& reference, const ColoredMesh& distorted,
                               const Msdm2Options& options) {
  const auto pool = [&](const std::vector<FeatureVector>& sums, int scales, DirectionResult& r) {
    std::vector<double> local(sums.size());
    for (std::size_t v = 0; v < sums.size(); ++v) local[v] = kMsdm2Local.apply(sums[v]) / scales;
    r.features = mean_features(sums);
    for (double& f : r.features) f /= scales;
    r.score = minkowski_pool(local, kMinkowskiExponent);
    if (options.per_vertex) r.local_distortion = std::move(local);
  };
  return detail::run_multiscale(reference, distorted, kMsdm2,
                                {options.direction, options.scales, nullptr}, pool);
}

}  // namespace qm3d::mesh
