#include "qm3d/mesh/cmdm.h"

#include "multiscale.h"

namespace qm3d::mesh {

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
  const detail::MultiscaleRun run{options.direction, options.scales, options.threads, table.get(),
                                  options.progress};
  return detail::run_multiscale(reference, distorted, detail::kCmdmDefinition, run, pool);
}

}  // namespace qm3d::mesh
