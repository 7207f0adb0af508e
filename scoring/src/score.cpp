#include "qm3d/scoring/score.h"

#include <stdexcept>

#include "qm3d/scoring/distortion_map.h"
#include "qm3d/common/error.h"
#include "qm3d/scoring/registry.h"

namespace qm3d::scoring {

std::vector<const MetricSpec*> metrics_for(const std::string& name, const Input& reference,
                                           const Input& distorted) {
  if (name == "compare") {
    auto all = default_registry().applicable(reference, distorted);
    if (all.empty()) {
      throw FormatError("no metric applies to " + reference.name() + " and " + distorted.name());
    }
    return all;
  }
  if (name == "auto") return {&default_registry().auto_metric(reference, distorted)};
  const MetricSpec* spec = default_registry().find(name);
  if (!spec) {
    std::string known;
    for (const auto& m : default_registry().metrics()) known += m.name + ", ";
    throw FormatError("unknown metric '" + name + "' (expected " + known + "compare or auto)");
  }
  return {spec};
}

RunOptions run_options_for(const MetricSpec& spec, const ScoreRequest& request) {
  RunOptions run = request.run;
  run.model.reset();
  if (request.model && spec.takes_model &&
      (request.model_any_metric || request.model->metric == spec.model_name())) {
    run.model = request.model;
  }
  return run;
}

MetricResult score(const MetricSpec& spec, const Input& reference, const Input& distorted,
                   const ScoreRequest& request, const std::filesystem::path& map) {
  if (!map.empty() && spec.per_element_on_input && !spec.per_element_on_inputs(reference, distorted)) {
    throw std::invalid_argument(
        "map: " + spec.name + " scores two meshes on their grid samples, not on their vertices, "
        "so there is no map on the meshes (sample them with qm3d sample --mode grid and score "
        "the clouds for a map)");
  }
  RunOptions run = run_options_for(spec, request);
  run.per_element = request.keep_per_element || !map.empty();
  if (request.release_inputs && map.empty()) {
    run.inputs_done = [&reference, &distorted] {
      reference.release();
      distorted.release();
    };
  }
  MetricResult result =
      run_metric(spec, reference, distorted, run, options_for(spec, request.options));
  if (!map.empty()) write_map(map, spec, result, reference, distorted);
  return result;
}

void write_map(const std::filesystem::path& map, const MetricSpec& spec, const MetricResult& result,
               const Input& reference, const Input& distorted) {
  const bool prefer_dist = spec.default_direction != Direction::kRefToDist;
  if (!spec.per_element_on_input) {
    const DirectionResult& d = result.any_direction(prefer_dist);
    if (!spec.per_element_positions || d.element_positions.empty()) {
      throw InputError(map.string() + ": " + spec.name +
                       " has no per-element values on its inputs to map");
    }
    // Values at their own positions (GeodesicPSIM's keypoints): a point cloud.
    write_distortion_map(map, d.element_positions, {}, d.per_element, d.per_element_values);
    return;
  }
  const DirectionResult& d = result.any_direction(prefer_dist);
  const bool on_distorted = result.dist_to_ref && &d == &*result.dist_to_ref;
  const Input& iterated = on_distorted ? distorted : reference;
  if (result.details.contains("keypoint_rows")) {  // graphsim: values on the keypoints
    std::vector<Vec3> at;
    for (const auto& row : result.details.at("keypoint_rows")) {
      at.push_back(reference.cloud().positions.at(row.get<std::size_t>()));
    }
    write_distortion_map(map, at, {}, d.per_element, d.per_element_values);
  } else if (spec.reads_for(reference, distorted) == Input::Kind::kMesh) {
    const ColoredMesh& m = iterated.mesh().mesh;
    write_distortion_map(map, m.positions, m.triangles, d.per_element, d.per_element_values);
  } else {
    write_distortion_map(map, iterated.cloud().positions, {}, d.per_element, d.per_element_values);
  }
}

}  // namespace qm3d::scoring
