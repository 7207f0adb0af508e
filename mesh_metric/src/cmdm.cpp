#include "qm3d/mesh/cmdm.h"

#include <chrono>

#include "mesh_inputs.h"
#include "multiscale.h"
#include "qm3d/mesh/metrics.h"
#include "qm3d/common/version.h"

namespace qm3d::mesh {

MetricResult compute_cmdm(const ColoredMesh& reference, const ColoredMesh& distorted,
                          const CmdmOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const std::filesystem::path data_dir = resolve_data_dir(options.data_dir);
  const auto table = Lab2000hlTable::shared(data_dir);
  const LinearModel& model = options.model ? *options.model : cmdm_model();
  const Direction direction = options.direction.value_or(kCmdmDefaultDirection);
  // CMDM = weights . (features averaged over vertices and scales) = mean local distortion
  // (MEPP2: sum over vertices / (n * scales), then the weights).
  const auto pool = [&](const std::vector<FeatureVector>& sums, int scales, DirectionResult& r) {
    const double count = static_cast<double>(sums.size()) * scales;
    FeatureVector total{};
    for (const auto& s : sums) {
      for (std::size_t k = 0; k < kNumFeatures; ++k) total[k] += s[k];
    }
    for (std::size_t k = 0; k < kNumFeatures; ++k) r.features[k] = total[k] / count;
    r.score = model.apply(r.features);
    if (!options.per_element) return;
    r.per_element.resize(sums.size());
    for (std::size_t v = 0; v < sums.size(); ++v) {
      r.per_element[v] = model.apply(sums[v]) / scales;
    }
  };
  const detail::MultiscaleRun run{direction, options.scales, options.threads, table.get(),
                                  options.progress, options.inputs_done};
  MetricResult result =
      detail::run_multiscale(reference, distorted, detail::kCmdmDefinition, run, pool);
  result.metric = "cmdm";
  result.feature_names = feature_names("f");
  result.provenance.version = kVersion;
  result.provenance.options = {{"direction", direction_name(direction)},
                               {"scales", options.scales},
                               {"weights", model.weights},
                               {"data_dir", data_dir.string()}};
  result.provenance.seconds = seconds_since(start);
  return result;
}

}  // namespace qm3d::mesh

namespace qm3d::mesh {

MetricSpec cmdm_spec() {
  MetricSpec s;
  s.name = "cmdm";
  s.title = "CMDM";
  s.reproduces = "MEPP-team/MEPP2 @ d977d05 (CMDM filter, example_CMDM)";
  s.summary = "CMDM between two coloured meshes (OBJ, OFF, PLY; textured OBJ coloured from its "
              "texture)";
  s.applies_to = AppliesTo::kMeshes;
  s.reads = Input::Kind::kMesh;
  s.default_direction = kCmdmDefaultDirection;
  s.direction_help = "symmetric: mean of both directions; dist-to-ref: distorted vertices matched "
                     "on the reference (MEPP2's test_cmdm); ref-to-dist: the reverse";
  s.takes_model = true;
  s.options = {{"scales", "Number of scales (curvature radius 0.001 + 0.0005 l of BB)", 3, {}, 1,
                100}};
  s.run = [](const MetricSpec& spec, const Input& ref, const Input& dist, const RunOptions& run,
             const OptionValues& values) {
    auto o = detail::with_run_options<CmdmOptions>(run);
    o.scales = values.at("scales").get<int>();
    std::vector<std::string> warnings = detail::reader_warnings(ref, dist);
    MetricResult r = compute_cmdm(detail::input_mesh(ref, true, spec.title),
                                  detail::input_mesh(dist, true, spec.title), o);
    detail::prepend_warnings(r, std::move(warnings));
    return r;
  };
  return s;
}

}  // namespace qm3d::mesh
