#include "qm3d/mesh/msdm2.h"

#include "multiscale.h"
#include "qm3d/common/pooling.h"

namespace qm3d::mesh {
namespace {

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
  const detail::MultiscaleRun run{options.direction, options.scales, options.threads, nullptr,
                                  options.progress};
  return detail::run_multiscale(reference, distorted, detail::kMsdm2Definition, run, pool);
}

}  // namespace qm3d::mesh
