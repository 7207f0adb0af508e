// D_LAB, the colour baseline of the CMDM report (Nehmé et al., "Colored mesh distortion
// measure", §1.3.2: "a classical color distance D_LAB, which is the average of the color
// difference (in LAB2000HL) computed symmetrically between the reference and the distorted
// model"). The report gives only that sentence; qm3d's definition:
// - Correspondence of each element e (vertex / point) of the iterated object on the other one:
//   two meshes: the closest point on the other mesh's surface, found as CMDM finds it, with the
//   colour there interpolated from the face's three vertex colours as CMDM interpolates its
//   colour features (LAB2000HL channels weighted by the Heron sub-triangle areas; the mesh
//   module's colour matcher, mesh_metric/src/surface_colours.cpp). Any other pair (two clouds,
//   a mesh and a cloud; a mesh is then read as its vertices, as PCQM reads it): the nearest
//   point of the other cloud as PCQM finds it (kd_tree.h, nanoflann 1.1.7's tree and order: the
//   first point the traversal reaches among equidistant ones), and that point's colour.
// - Colours: sRGB -> CIELab -> LAB2000HL as CMDM and PCQM convert them (common/color.h, the
//   shared tables).
// - Per-element value: dE(e) = the Euclidean distance in LAB2000HL between e's colour and its
//   correspondence's, sqrt(dL^2 + da^2 + db^2) (LAB2000HL is built so that this distance
//   approximates CIEDE2000; no further CIEDE2000 formula is applied).
// - Direction score: the mean of dE over the iterated object's elements (summed in element order:
//   the same bits for any thread count). Symmetric (the default): the mean of the two
//   directions. A distortion: 0 for identical colours at identical positions.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "kd_tree.h"
#include "qm3d/common/color.h"
#include "qm3d/common/error.h"
#include "qm3d/common/metric.h"
#include "qm3d/common/version.h"
#include "qm3d/pointcloud/metrics.h"

namespace qm3d::pointcloud {
namespace {

/// Queries per chunk of the parallel search (each element's match is its own: the results do not
/// depend on the schedule or the thread count).
constexpr int kChunk = 1024;

int thread_count(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

double lab_distance(const Lab& x, const Lab& y) {
  const double dl = x.L - y.L, da = x.a - y.a, db = x.b - y.b;
  return std::sqrt(dl * dl + da * da + db * db);
}

/// dE per element of `own` against `matched` (the same length).
std::vector<double> distances(const std::vector<Lab>& own, const std::vector<Lab>& matched) {
  std::vector<double> out(own.size());
  for (std::size_t i = 0; i < own.size(); ++i) out[i] = lab_distance(own[i], matched[i]);
  return out;
}

void check_cloud(const ColoredCloud& c, const std::string& name) {
  if (c.positions.empty()) throw NumericError("dlab: " + name + ": the cloud is empty");
  if (c.colors.size() != c.positions.size()) {
    throw FormatError(name +
                      ": no vertex colours (dlab compares colours: one colour per point "
                      "needed; expected red/green/blue vertex properties)");
  }
  for (std::size_t i = 0; i < c.positions.size(); ++i) {
    for (double v : c.positions[i]) {
      if (!std::isfinite(v)) {
        throw NumericError("dlab: " + name + ": point " + std::to_string(i) +
                           " has a non-finite coordinate");
      }
    }
  }
}

/// The LAB2000HL colour of each point of `iterated` and of its nearest point in `other`
/// (PCQM's tree and search: kd_tree.h knn_search with k = 1).
SurfaceColours nearest_colours(const ColoredCloud& iterated, const ColoredCloud& other,
                               const Lab2000hlTable& table, int threads) {
  const detail::KdTree tree(other.positions, threads);
  const std::vector<Lab> other_lab = to_lab2000hl(other.colors, table);
  SurfaceColours out;
  out.own = to_lab2000hl(iterated.colors, table);
  out.matched.resize(iterated.positions.size());
  const long n = static_cast<long>(iterated.positions.size());
#pragma omp parallel num_threads(thread_count(threads))
  {
    std::vector<detail::Neighbour> nearest;
#pragma omp for schedule(dynamic, kChunk)
    for (long i = 0; i < n; ++i) {
      tree.knn_search(iterated.positions[static_cast<std::size_t>(i)], 1, nearest);
      out.matched[static_cast<std::size_t>(i)] =
          other_lab[tree.input_index()[nearest.front().index]];
    }
  }
  return out;
}

DirectionResult direction_result(const SurfaceColours& colours, bool per_element) {
  std::vector<double> de = distances(colours.own, colours.matched);
  double sum = 0, largest = 0;
  for (double v : de) {  // in element order: the same bits for any thread count
    sum += v;
    largest = std::max(largest, v);
  }
  DirectionResult d;
  d.score = sum / static_cast<double>(de.size());
  d.features.fill(0.0);
  d.values = {{"delta_e_mean", d.score}, {"delta_e_max", largest}};
  if (per_element) d.per_element = std::move(de);
  return d;
}

/// The symmetric values: the mean of the two means (the score), the larger maximum.
NamedValues symmetric_values(const DirectionResult& a, const DirectionResult& b) {
  return {{"delta_e_mean", (a.score + b.score) / 2},
          {"delta_e_max",
           std::max(*find_value(a.values, "delta_e_max"), *find_value(b.values, "delta_e_max"))}};
}

// The colours of one direction: by the mesh module's projection for two meshes, else by PCQM's
// nearest neighbour.
SurfaceColours direction_colours(const SurfaceColourMatcher& on_surfaces, const Input& iterated,
                                 const Input& other, bool meshes, const Lab2000hlTable& table,
                                 int threads) {
  if (meshes) {
    SurfaceColours c = on_surfaces(iterated, other, table, threads);
    if (c.own.empty())
      throw NumericError("dlab: " + iterated.name() + ": the mesh has no vertices");
    return c;
  }
  return nearest_colours(iterated.cloud(), other.cloud(), table, threads);
}

/// Adds each warning not given yet (both directions repair the same meshes alike).
void add_warnings(MetricResult& result, const std::vector<std::string>& warnings) {
  for (const std::string& w : warnings) {
    if (std::find(result.warnings.begin(), result.warnings.end(), w) == result.warnings.end()) {
      result.warnings.push_back(w);
    }
  }
}

MetricResult run_dlab(const SurfaceColourMatcher& on_surfaces, const Input& ref, const Input& dist,
                      const RunOptions& run) {
  const auto start = std::chrono::steady_clock::now();
  const bool meshes = on_surfaces && ref.is_mesh() && dist.is_mesh();
  if (!meshes) {
    check_cloud(ref.cloud(), ref.name());
    check_cloud(dist.cloud(), dist.name());
  }
  const std::filesystem::path data_dir = resolve_data_dir(run.data_dir);
  const auto table = Lab2000hlTable::shared(data_dir);
  const Direction dir = run.direction.value_or(Direction::kSymmetric);
  MetricResult result;
  result.metric = "dlab";
  if (meshes) add_warnings(result, ref.mesh().warnings);
  if (meshes) add_warnings(result, dist.mesh().warnings);
  if (dir != Direction::kDistToRef) {
    const SurfaceColours c = direction_colours(on_surfaces, ref, dist, meshes, *table, run.threads);
    add_warnings(result, c.warnings);
    result.ref_to_dist = direction_result(c, run.per_element);
  }
  if (dir != Direction::kRefToDist) {
    const SurfaceColours c = direction_colours(on_surfaces, dist, ref, meshes, *table, run.threads);
    add_warnings(result, c.warnings);
    result.dist_to_ref = direction_result(c, run.per_element);
  }
  if (run.inputs_done) run.inputs_done();
  combine_directions(result);
  result.values = result.ref_to_dist && result.dist_to_ref
                      ? symmetric_values(*result.ref_to_dist, *result.dist_to_ref)
                      : result.any_direction().values;
  const char* correspondence = meshes ? "closest point on the other surface (CMDM's projection)"
                                      : "nearest point of the other cloud (PCQM's k-d tree)";
  result.details = {{"correspondence", correspondence}};
  result.text_note = std::string("[LAB2000HL colour distance to the ") + correspondence + "]";
  result.provenance.version = kVersion;
  result.provenance.options = {{"direction", direction_name(dir)},
                               {"correspondence", meshes ? "surface" : "nearest point"},
                               {"data_dir", data_dir.string()}};
  result.provenance.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace

MetricSpec dlab_spec(SurfaceColourMatcher on_surfaces) {
  MetricSpec s;
  s.name = "dlab";
  s.title = "D_LAB";
  s.summary =
      "D_LAB, the colour baseline of the CMDM report: mean LAB2000HL colour distance between each "
      "vertex / point and its correspondence on the other object (meshes: CMDM's closest point "
      "on the surface; clouds: PCQM's nearest point)";
  s.higher_is_better = false;
  s.applies_to = AppliesTo::kBoth;
  s.reads = Input::Kind::kCloud;
  s.reads_two_meshes_as_meshes = static_cast<bool>(on_surfaces);
  s.default_direction = Direction::kSymmetric;
  s.direction_help =
      "symmetric: mean of both directions (the report's \"computed symmetrically\"); "
      "ref-to-dist: the reference's vertices / points matched on the distorted object; "
      "dist-to-ref: the distorted object's matched on the reference";
  s.symmetric_rule = "mean";
  s.per_element_on_input = true;
  s.value_names = {"delta_e_mean", "delta_e_max"};
  s.run = [on_surfaces](const MetricSpec&, const Input& ref, const Input& dist,
                        const RunOptions& run, const OptionValues&) {
    check_thread_count(run.threads);
    return run_dlab(on_surfaces, ref, dist, run);
  };
  return s;
}

}  // namespace qm3d::pointcloud
