#include "qm3d/mesh/msdm2.h"

#include <chrono>
#include <stdexcept>

#include "mesh_inputs.h"
#include "multiscale.h"
#include "qm3d/mesh/metrics.h"
#include "qm3d/common/version.h"
#include "qm3d/common/pooling.h"

namespace qm3d::mesh {
namespace {

// Local score (f1 + f2 + 0.5 f3) / (2 + 0.5) (msdm2.h compute_statistics, param = 0.5), and
// Minkowski pooling with p = 3 (process_msdm2_multires).
const LinearModel kMsdm2Local{"msdm2", {0.4, 0.4, 0.2, 0, 0, 0, 0, 0},
                              "Lavoue 2011; MEPP2 msdm2.h: (f1 + f2 + 0.5 f3) / 2.5"};
constexpr double kMinkowskiExponent = 3.0;

}  // namespace

MetricResult compute_msdm2(const ColoredMesh& reference, const ColoredMesh& distorted,
                           const Msdm2Options& options) {
  const auto start = std::chrono::steady_clock::now();
  if (options.model) {
    throw std::invalid_argument("MSDM2 has no linear model: weights and model files do not apply");
  }
  const Direction direction = options.direction.value_or(kMsdm2DefaultDirection);
  const auto pool = [&](const std::vector<FeatureVector>& sums, int scales, DirectionResult& r) {
    std::vector<double> local(sums.size());
    for (std::size_t v = 0; v < sums.size(); ++v) local[v] = kMsdm2Local.apply(sums[v]) / scales;
    r.features = mean_features(sums);
    for (double& f : r.features) f /= scales;
    r.score = minkowski_pool(local, kMinkowskiExponent);
    if (options.per_element) r.per_element = std::move(local);
  };
  const detail::MultiscaleRun run{direction, options.scales, options.threads, nullptr,
                                  options.progress, options.inputs_done};
  MetricResult result =
      detail::run_multiscale(reference, distorted, detail::kMsdm2Definition, run, pool);
  result.metric = "msdm2";
  result.feature_names = feature_names("f");
  result.provenance.version = kVersion;
  result.provenance.options = {{"direction", direction_name(direction)},
                               {"scales", options.scales}};
  result.provenance.seconds = seconds_since(start);
  return result;
}

}  // namespace qm3d::mesh

namespace qm3d::mesh {

MetricSpec msdm2_spec() {
  MetricSpec s;
  s.name = "msdm2";
  s.title = "MSDM2";
  s.reproduces = "MEPP-team/MEPP2 @ d977d05 (MSDM2 filter, example_msdm2)";
  s.summary = "MSDM2 (geometry only; colours ignored) between two meshes (OBJ, OFF, PLY)";
  s.applies_to = AppliesTo::kMeshes;
  s.reads = Input::Kind::kMesh;
  s.default_direction = kMsdm2DefaultDirection;
  s.direction_help = "dist-to-ref (MEPP2's example_msdm2), ref-to-dist or symmetric";
  s.options = {{"scales", "Number of scales (curvature radius (0.002 + 0.001 l) of BB)", 3, {}, 1,
                100}};
  s.run = [](const MetricSpec& spec, const Input& ref, const Input& dist, const RunOptions& run,
             const OptionValues& values) {
    auto o = detail::with_run_options<Msdm2Options>(run);
    o.scales = values.at("scales").get<int>();
    std::vector<std::string> warnings = detail::reader_warnings(ref, dist);
    MetricResult r = compute_msdm2(detail::input_mesh(ref, false, spec.title),
                                   detail::input_mesh(dist, false, spec.title), o);
    detail::prepend_warnings(r, std::move(warnings));
    return r;
  };
  return s;
}

}  // namespace qm3d::mesh
