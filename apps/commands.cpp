#include "commands.h"

#include <chrono>
#include <future>

#include "distortion_map.h"
#include "qm3d/common/color.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/ply.h"
#include "qm3d/mesh/mesh_io.h"
#include "qm3d/mesh/texture.h"
#include "qm3d/pointcloud/cloud_io.h"

namespace qm3d::app {
namespace {

DirectionReport to_report(double score, const FeatureVector& f, double bb) {
  return DirectionReport{score, f, bb};
}

MetricReport new_report(const char* metric, const std::filesystem::path& reference,
                        const std::filesystem::path& distorted, nlohmann::json options,
                        double score) {
  MetricReport r;
  r.metric = metric;
  r.reference = reference.string();
  r.distorted = distorted.string();
  r.options = std::move(options);
  r.score = score;
  return r;
}

// Metric errors name "reference" and "distorted": say which files those are.
template <typename F>
auto naming_inputs(const std::filesystem::path& reference, const std::filesystem::path& distorted,
                   const F& compute) {
  try {
    return compute();
  } catch (const NumericError& e) {
    throw NumericError(e.what() + std::string(" (reference ") + reference.string() +
                       ", distorted " + distorted.string() + ")");
  }
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

nlohmann::json cmdm_options_json(const mesh::CmdmOptions& o) {
  return {{"direction", direction_name(o.direction)},
          {"scales", o.scales},
          {"weights", o.model.weights},
          {"data_dir", resolve_data_dir(o.data_dir).string()}};
}

nlohmann::json pcqm_options_json(const pointcloud::PcqmOptions& o) {
  return {{"radius", o.radius_rel},   {"knn", o.knn},
          {"rx", o.radius_factor},    {"bbox", bbox_mode_name(o.bbox)},
          {"symmetric", o.symmetric}, {"data_dir", resolve_data_dir(o.data_dir).string()}};
}

}  // namespace

std::string direction_name(mesh::Direction d) {
  switch (d) {
    case mesh::Direction::kSymmetric: return "symmetric";
    case mesh::Direction::kDistToRef: return "dist-to-ref";
    case mesh::Direction::kRefToDist: return "ref-to-dist";
  }
  return "?";
}

std::string bbox_mode_name(pointcloud::BboxMode m) {
  return m == pointcloud::BboxMode::kReference ? "reference" : "extent";
}

ColoredCloud load_cloud(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  if (ext == "obj" || ext == "off") return mesh::read_mesh_vertices(path);
  return pointcloud::read_cloud(path);
}

bool is_mesh_file(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  if (ext == "obj" || ext == "off") return true;
  if (ext != "ply") return false;
  const ply::Header h = ply::parse_header(read_file_bytes(path), path.string());
  for (const auto& e : h.elements) {
    if (e.name == "face" && e.count > 0) return true;
  }
  return false;
}

namespace {

void add_mesh_directions(const mesh::MeshMetricResult& r, MetricReport& report) {
  if (r.dist_to_ref) {
    report.dist_to_ref =
        to_report(r.dist_to_ref->score, r.dist_to_ref->features, r.dist_to_ref->bbox_max_side);
  }
  if (r.ref_to_dist) {
    report.ref_to_dist =
        to_report(r.ref_to_dist->score, r.ref_to_dist->features, r.ref_to_dist->bbox_max_side);
  }
}

// The iterated mesh, coloured by its local distortion (dist->ref when computed, like MEPP2).
void write_mesh_map(const std::filesystem::path& map, const mesh::MeshMetricResult& r,
                    const mesh::MeshFile& ref, const mesh::MeshFile& dist) {
  const bool on_distorted = r.dist_to_ref.has_value();
  const auto& m = on_distorted ? dist.mesh : ref.mesh;
  write_distortion_map(map, m.positions, m.triangles,
                       on_distorted ? r.dist_to_ref->local_distortion
                                    : r.ref_to_dist->local_distortion);
}

// How the two inputs of a pair are read (or sampled): concurrently, unless the metric was given
// one thread (--threads 1 keeps one core busy).
std::launch input_launch(int threads) {
  return threads == 1 ? std::launch::deferred : std::launch::async;
}

// Reads both meshes, runs `compute`, and reports it.
template <typename Compute>
MetricReport run_mesh_metric(const char* metric, const std::filesystem::path& reference,
                             const std::filesystem::path& distorted, nlohmann::json options,
                             bool require_colors, int threads, const std::filesystem::path& map,
                             const Compute& compute) {
  const auto start = std::chrono::steady_clock::now();
  auto ref_task = std::async(input_launch(threads),
                             [&] { return mesh::read_mesh(reference, {require_colors}); });
  const mesh::MeshFile dist = mesh::read_mesh(distorted, {require_colors});
  const mesh::MeshFile ref = ref_task.get();
  const mesh::MeshMetricResult r = naming_inputs(
      reference, distorted, [&] { return compute(ref.mesh, dist.mesh, !map.empty()); });
  MetricReport report = new_report(metric, reference, distorted, std::move(options), r.score);
  add_mesh_directions(r, report);
  for (const auto& warnings : {ref.warnings, dist.warnings, r.warnings}) {
    report.warnings.insert(report.warnings.end(), warnings.begin(), warnings.end());
  }
  if (!map.empty()) write_mesh_map(map, r, ref, dist);
  report.seconds = seconds_since(start);
  return report;
}

}  // namespace

MetricReport run_cmdm(const std::filesystem::path& reference, const std::filesystem::path& distorted,
                      const mesh::CmdmOptions& options, const std::filesystem::path& map) {
  return run_mesh_metric("cmdm", reference, distorted, cmdm_options_json(options), true,
                         options.threads, map,
                         [&](const ColoredMesh& r, const ColoredMesh& d, bool per_vertex) {
                           mesh::CmdmOptions o = options;
                           o.per_vertex = per_vertex;
                           return mesh::compute_cmdm(r, d, o);
                         });
}

MetricReport run_msdm2(const std::filesystem::path& reference,
                       const std::filesystem::path& distorted, const mesh::Msdm2Options& options,
                       const std::filesystem::path& map) {
  const nlohmann::json json = {{"direction", direction_name(options.direction)},
                               {"scales", options.scales}};
  return run_mesh_metric("msdm2", reference, distorted, json, false, options.threads, map,
                         [&](const ColoredMesh& r, const ColoredMesh& d, bool per_vertex) {
                           mesh::Msdm2Options o = options;
                           o.per_vertex = per_vertex;
                           return mesh::compute_msdm2(r, d, o);
                         });
}

namespace {

// PCQM on two clouds already in memory, reported under `metric`.
MetricReport pcqm_report(const char* metric, const std::filesystem::path& reference,
                         const std::filesystem::path& distorted, const ColoredCloud& ref,
                         const ColoredCloud& dist, nlohmann::json options_json,
                         const pointcloud::PcqmOptions& options,
                         const std::filesystem::path& map) {
  pointcloud::PcqmOptions o = options;
  o.per_point = !map.empty();
  const pointcloud::PcqmResult r =
      naming_inputs(reference, distorted, [&] { return pointcloud::compute_pcqm(ref, dist, o); });
  MetricReport report = new_report(metric, reference, distorted, std::move(options_json), r.score);
  report.ref_to_dist =
      to_report(r.ref_to_dist.score, r.ref_to_dist.features, r.ref_to_dist.bbox_max_side);
  if (r.dist_to_ref) {
    report.dist_to_ref =
        to_report(r.dist_to_ref->score, r.dist_to_ref->features, r.dist_to_ref->bbox_max_side);
  }
  report.warnings = r.warnings;
  if (!map.empty()) write_distortion_map(map, ref.positions, {}, r.ref_to_dist.per_point);
  return report;
}

nlohmann::json sampling_json(const mesh::SamplingOptions& o) {
  return {{"points", o.points}, {"density", o.density}, {"seed", o.seed}};
}

}  // namespace

MetricReport run_pcqm(const std::filesystem::path& reference, const std::filesystem::path& distorted,
                      const pointcloud::PcqmOptions& options, const std::filesystem::path& map) {
  const auto start = std::chrono::steady_clock::now();
  auto ref_task = std::async(input_launch(options.threads), [&] { return load_cloud(reference); });
  const ColoredCloud dist = load_cloud(distorted);
  const ColoredCloud ref = ref_task.get();
  MetricReport report = pcqm_report("pcqm", reference, distorted, ref, dist,
                                    pcqm_options_json(options), options, map);
  report.seconds = seconds_since(start);
  return report;
}

ColoredCloud sample_mesh_file(const std::filesystem::path& path,
                              const mesh::SamplingOptions& options) {
  if (lower_extension(path) != "obj") return mesh::sample_surface(mesh::read_mesh(path).mesh, options);
  // A textured OBJ is sampled from its texture at each sample's UV; the file is read once.
  const std::string bytes = read_file_bytes(path);
  if (mesh::obj_is_textured(bytes)) {
    return mesh::sample_surface(mesh::parse_textured_obj(bytes, path), options);
  }
  return mesh::sample_surface(mesh::parse_mesh(bytes, mesh::MeshFormat::kObj, path.string()).mesh,
                              options);
}

MetricReport run_pcqm_sampled(const std::filesystem::path& reference,
                              const std::filesystem::path& distorted,
                              const MetricOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const auto sample = [&](const std::filesystem::path& path) {
    try {
      return sample_mesh_file(path, options.sampling);
    } catch (const NumericError& e) {
      throw NumericError(path.string() + ": " + e.what());
    }
  };
  auto ref_task = std::async(input_launch(options.pcqm.threads), [&] { return sample(reference); });
  const ColoredCloud dist = sample(distorted);
  const ColoredCloud ref = ref_task.get();
  nlohmann::json json = pcqm_options_json(options.pcqm);
  json["sampling"] = sampling_json(options.sampling);
  MetricReport report =
      pcqm_report("pcqm_sampled", reference, distorted, ref, dist, json, options.pcqm, {});
  report.seconds = seconds_since(start);
  return report;
}

std::vector<std::string> compare_metrics(const std::filesystem::path& reference,
                                         const std::filesystem::path& distorted) {
  if (is_mesh_file(reference) && is_mesh_file(distorted)) {
    return {"cmdm", "msdm2", "pcqm", "pcqm_sampled"};
  }
  return {"pcqm"};
}

std::vector<MetricReport> run_compare(const std::filesystem::path& reference,
                                      const std::filesystem::path& distorted,
                                      const MetricOptions& options) {
  std::vector<MetricReport> reports;
  for (const std::string& metric : compare_metrics(reference, distorted)) {
    reports.push_back(run_metric(metric, reference, distorted, options));
  }
  return reports;
}

MetricReport run_metric(const std::string& metric, const std::filesystem::path& reference,
                        const std::filesystem::path& distorted, const MetricOptions& options) {
  if (metric == "cmdm") return run_cmdm(reference, distorted, options.cmdm);
  if (metric == "msdm2") return run_msdm2(reference, distorted, options.msdm2);
  if (metric == "pcqm") return run_pcqm(reference, distorted, options.pcqm);
  if (metric == "pcqm_sampled") return run_pcqm_sampled(reference, distorted, options);
  throw FormatError("unknown metric '" + metric +
                    "' (expected cmdm, msdm2, pcqm, pcqm_sampled, compare or auto)");
}

}  // namespace qm3d::app
