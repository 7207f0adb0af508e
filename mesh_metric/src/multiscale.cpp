#include "multiscale.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <future>
#include <list>
#include <optional>
#include <stdexcept>

#include "curvature.h"
#include "halfedge_mesh.h"
#include "neighbourhood.h"
#include "qm3d/common/error.h"
#include "qm3d/common/metric.h"
#include "qm3d/common/warning.h"

namespace qm3d::mesh::detail {
namespace {

// Up to this many faces (both meshes together) the two directions' AABB trees are built and
// queried concurrently (~200 B per face at the peak).
constexpr std::size_t kConcurrentMatchFaces = 1000000;

// A mesh ready for the metric, with what both directions need of it.
struct PreparedMesh {
  HalfedgeMesh mesh;
  std::vector<Lab> lab;  ///< LAB2000HL per vertex (empty when colour is not used)
  double box_size = 0;
  std::size_t input_vertices = 0;
};

double longest_side(const HalfedgeMesh& m, const std::string& name) {
  const double bb = bounding_box(m.positions.begin(), m.positions.end()).longest_side();
  if (!(bb > 0) || !std::isfinite(bb)) {
    throw NumericError(name + ": bounding box has zero size (all vertices identical)");
  }
  return bb;
}

// LAB2000HL colour of each vertex of the metric's mesh (duplicated vertices share the input's).
std::vector<Lab> vertex_lab2000hl(const HalfedgeMesh& m, const ColoredMesh& input,
                                  const Lab2000hlTable& table, const std::string& name) {
  if (input.colors.size() != input.positions.size()) {
    throw FormatError(name + ": " + std::to_string(input.colors.size()) + " colours for " +
                      std::to_string(input.positions.size()) + " vertices");
  }
  std::vector<Lab> lab = to_lab2000hl(input.colors, table);
  for (std::size_t v = lab.size(); v < m.input_vertex.size(); ++v)
    lab.push_back(lab[m.input_vertex[v]]);
  return lab;
}

// MEPP2's curvature ignores edges shorter than 1.5e-8 whatever the mesh's size (kClipEpsilon):
// reproduced, and said. Edges of length zero (vertices merged onto one position, as a quantiser
// does) are inside every sphere at any scale: nothing to scale, only to weld. The others make
// the curvature features depend on the mesh's scale: scaling up helps when the mesh is small.
void warn_small_edges(HalfedgeMesh& m, const std::string& name, double box_size) {
  const ShortEdges edges = edges_under_clip_epsilon(m);
  if (edges.zero > 0) {
    m.warnings.push_back(
        make_warning(name,
                     std::to_string(edges.zero) +
                         " edges have zero length (distinct vertices at one position, e.g. "
                         "merged by quantisation)",
                     "weld duplicate vertices if unintended")
            .line);
  }
  if (edges.tiny == 0) return;
  // A mesh whose box is below this has its detail near MEPP2's absolute epsilon: scale it up.
  constexpr double kSmallBox = 1e-3;
  const std::string remedy = box_size < kSmallBox ? "scale both meshes up to a box of about 1"
                                                  : "weld near-coincident vertices";
  m.warnings.push_back(make_warning(name,
                                    std::to_string(edges.tiny) +
                                        " edges are shorter than 1.5e-8, MEPP2's absolute "
                                        "epsilon: curvature depends on scale",
                                    remedy)
                           .line);
}

PreparedMesh prepare(const ColoredMesh& input, const std::string& name, const MultiscaleRun& run,
                     const MultiscaleDefinition& def, int threads) {
  PreparedMesh p;
  p.mesh = build_halfedge_mesh(input, name, def.degenerate_edges, threads);
  // A caller that frees its inputs early trades their colours for a copy of the geometry.
  if (run.inputs_done) p.mesh.detach();
  if (def.uses_color) p.lab = vertex_lab2000hl(p.mesh, input, *run.colors, name);
  p.box_size = longest_side(p.mesh, name);
  p.input_vertices = input.positions.size();
  warn_small_edges(p.mesh, name, p.box_size);
  return p;
}

// Values of the other mesh interpolated at each matched point, for each of `fields` at once
// (each value on its own: parallel).
std::vector<std::vector<double>> interpolate_all(
    const std::vector<SurfaceMatch>& matches, const HalfedgeMesh& other,
    const std::vector<const std::vector<double>*>& fields, int threads) {
  std::vector<std::vector<double>> out(fields.size(), std::vector<double>(matches.size()));
  const auto n = static_cast<std::int64_t>(matches.size());
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::int64_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < fields.size(); ++j) {
      out[j][i] = interpolate(matches[i], other.triangles[matches[i].face], *fields[j]);
    }
  }
  return out;
}

std::vector<Lab> interpolate_colors(const std::vector<SurfaceMatch>& matches,
                                    const HalfedgeMesh& other, const std::vector<Lab>& colors,
                                    int threads) {
  std::vector<Lab> out(matches.size());
  const auto n = static_cast<std::int64_t>(matches.size());
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::int64_t i = 0; i < n; ++i) {
    const SurfaceMatch& m = matches[i];
    const Triangle& t = other.triangles[m.face];
    for (double Lab::*c : {&Lab::L, &Lab::a, &Lab::b}) {
      out[i].*c = interpolate(m, colors[t[0]].*c, colors[t[1]].*c, colors[t[2]].*c);
    }
  }
  return out;
}

// Processed curvatures of a mesh at several radii, remembered for the other direction when both
// directions use the same radii (same bounding-box size, e.g. colour-only distortions).
class CurvatureCache {
 public:
  CurvatureCache(CurvatureVariant variant, bool reuse, int threads)
      : variant_(variant), reuse_(reuse), threads_(threads) {}

  /// The curvature of `mesh` at each of `radii` (increasing), those not yet known computed in
  /// one walk per vertex; the references stay valid until release(mesh).
  std::vector<const std::vector<double>*> get(const HalfedgeMesh& mesh,
                                              const std::vector<double>& radii, double maxdim,
                                              LoopProgress* progress = nullptr) {
    std::vector<double> missing;
    for (double r : radii) {
      if (!find(mesh, r, maxdim)) missing.push_back(r);
    }
    if (!missing.empty()) {
      auto values = processed_curvatures(mesh, missing, maxdim, variant_, threads_, progress);
      for (std::size_t j = 0; j < missing.size(); ++j) {
        entries_.push_back({&mesh, missing[j], maxdim, std::move(values[j])});
      }
    }
    std::vector<const std::vector<double>*> out;
    for (double r : radii) out.push_back(find(mesh, r, maxdim));
    return out;
  }
  /// Frees `mesh`'s curvatures unless the other direction will use them (a list: erasing keeps
  /// the references to the other entries valid).
  void release(const HalfedgeMesh& mesh) {
    if (!reuse_) entries_.remove_if([&](const Entry& e) { return e.mesh == &mesh; });
  }

 private:
  struct Entry {
    const HalfedgeMesh* mesh;
    double radius, maxdim;
    std::vector<double> values;
  };
  const std::vector<double>* find(const HalfedgeMesh& mesh, double radius, double maxdim) const {
    for (const Entry& e : entries_) {
      if (e.mesh == &mesh && e.radius == radius && e.maxdim == maxdim) return &e.values;
    }
    return nullptr;
  }
  CurvatureVariant variant_;
  bool reuse_;
  int threads_;
  std::list<Entry> entries_;
};

// One walk per vertex serves at most this many scales (each scale in a walk keeps two curvature
// values per vertex: 10 MB per scale on a 655k-vertex mesh).
constexpr int kScalesPerWalk = 8;

// Adds each vertex's features at the scales of `levels` to the running sums, scale by scale.
void accumulate_scales(const std::vector<MatchedFields>& levels,
                       const std::vector<WalkParameters>& walks,
                       const FeatureConventions& conventions, std::vector<FeatureVector>& sums,
                       int threads, ProgressSteps& progress) {
  const auto n = static_cast<std::int64_t>(sums.size());
  LoopProgress done(&progress, sums.size());
  const bool with_color = levels.front().color != nullptr;
#pragma omp parallel num_threads(threads)
  {
    MultiWalkScratch scratch;
    std::vector<NeighbourhoodSamples> samples;
#pragma omp for schedule(dynamic, 512)
    for (std::int64_t v = 0; v < n; ++v) {
      sample_neighbourhoods(levels, static_cast<std::uint32_t>(v), walks, scratch, samples);
      for (const NeighbourhoodSamples& s : samples) {
        const FeatureVector f =
            with_color ? local_features(s, conventions) : curvature_features(s, conventions);
        for (std::size_t k = 0; k < kNumFeatures; ++k) sums[v][k] += f[k];
      }
      done.add();
    }
  }
  done.finish();
}

// One direction: the features of `first`'s vertices matched on `second`, summed over scales.
std::vector<FeatureVector> direction_sums(const PreparedMesh& iterated, const PreparedMesh& other,
                                          const MultiscaleDefinition& def, int scales, int threads,
                                          CurvatureCache& curvatures, SurfaceMatches matching,
                                          const std::string& label, ProgressSteps& progress) {
  const auto& [matched_point, matches] = matching;
  std::vector<Lab> lab_match;
  if (def.uses_color) lab_match = interpolate_colors(matches, other.mesh, other.lab, threads);
  const double maxdim = iterated.box_size;
  std::vector<FeatureVector> sums(iterated.mesh.positions.size(), FeatureVector{});
  double rc = def.first_radius;  // accumulated like MEPP2's `radius_curvature +=`
  for (int first = 0; first < scales; first += kScalesPerWalk) {
    const int end = std::min(scales, first + kScalesPerWalk);
    // "scales 1-3", or "scales 9-16 of 20" when one walk cannot serve them all.
    std::string which = end - first == 1
                            ? "scale " + std::to_string(end)
                            : "scales " + std::to_string(first + 1) + "-" + std::to_string(end);
    if (end - first < scales) which += " of " + std::to_string(scales);
    std::vector<double> radii;
    std::vector<WalkParameters> walks;
    for (int level = first; level < end; ++level) {
      radii.push_back(maxdim * rc);
      const double h = rc * def.neighbourhood_factor * maxdim;
      walks.push_back({h, h / def.sigma_divisor, def.strict_outward_test});
      rc += def.radius_step;
    }
    progress.begin(label + ": curvature, " + which, end - first);
    LoopProgress curvature_done(&progress,
                                other.mesh.positions.size() + iterated.mesh.positions.size());
    // The other mesh's first: only their values at the matched points are kept.
    std::vector<std::vector<double>> curv_match = interpolate_all(
        matches, other.mesh, curvatures.get(other.mesh, radii, maxdim, &curvature_done), threads);
    curvatures.release(other.mesh);
    const auto curv1 = curvatures.get(iterated.mesh, radii, maxdim, &curvature_done);
    curvature_done.finish();
    std::vector<MatchedFields> levels;
    for (int j = 0; j < end - first; ++j) {
      levels.push_back({&iterated.mesh, &matched_point, curv1[j], &curv_match[j],
                        def.uses_color ? &iterated.lab : nullptr,
                        def.uses_color ? &lab_match : nullptr});
    }
    progress.begin(label + ": neighbourhoods, " + which, end - first);
    accumulate_scales(levels, walks, def.conventions, sums, threads, progress);
    curvatures.release(iterated.mesh);
  }
  return sums;
}

SurfaceMatches match(const PreparedMesh& iterated, const PreparedMesh& other,
                     const MultiscaleDefinition& def, int threads) {
  return match_to_surface(iterated.mesh.positions, other.mesh, def.anchor, threads);
}

DirectionResult run_direction(const PreparedMesh& iterated, const PreparedMesh& other,
                              const MultiscaleDefinition& def, int scales, int threads,
                              CurvatureCache& curvatures, const DirectionPooling& pool,
                              std::optional<SurfaceMatches> matching, const std::string& label,
                              ProgressSteps& progress) {
  DirectionResult result;
  result.box_size = iterated.box_size;
  if (!matching) {
    progress.begin(label + ": closest points");
    matching = match(iterated, other, def, threads);
  }
  auto sums = direction_sums(iterated, other, def, scales, threads, curvatures,
                             std::move(*matching), label, progress);
  // Duplicated (non-manifold) vertices come after the input's: report the input's vertices.
  pool(sums, scales, result);
  if (result.per_element.size() > iterated.input_vertices) {
    result.per_element.resize(iterated.input_vertices);
  }
  return result;
}

}  // namespace

MetricResult run_multiscale(const ColoredMesh& reference, const ColoredMesh& distorted,
                            const MultiscaleDefinition& def, const MultiscaleRun& run,
                            const DirectionPooling& pool) {
  if (run.scales < 1 || run.scales > 100) {
    throw std::invalid_argument(std::string(def.name) +
                                ": the number of scales must be between 1 and 100");
  }
  check_thread_count(run.threads);  // libgomp crashes on tens of thousands
  const bool both = run.direction == Direction::kSymmetric;
  // Steps of about equal cost: preparing, then per direction its matching, each scale's
  // curvature and each scale's neighbourhoods.
  ProgressSteps progress(run.progress, 1 + (both ? 2 : 1) * (1 + 2 * run.scales));
  progress.begin("connectivity");
  // Every parallel part gets an explicit thread count: OpenMP regions started from a std::async
  // task would otherwise use the default, not the caller's setting. Two concurrent tasks share
  // the threads, and with one thread nothing runs concurrently.
  const int threads = run.threads > 0 ? run.threads : omp_get_max_threads();
  const bool concurrent = threads >= 2;
  const int per_task = concurrent ? threads / 2 : 1;
  // The two meshes are prepared concurrently. When both directions are needed and the meshes
  // are small, each task goes on to build the closest-point structures of its mesh (the target
  // of the other direction), and both directions' queries then share the threads in one loop;
  // large meshes are matched one direction at a time, later, to keep the memory peak low.
  PreparedMesh ref, dist;
  std::optional<SurfaceTarget> ref_target, dist_target;
  const bool match_early =
      concurrent && both &&
      reference.triangles.size() + distorted.triangles.size() <= kConcurrentMatchFaces;
  const auto prepare_ref = [&] {
    ref = prepare(reference, "reference mesh", run, def, per_task);
    if (match_early) ref_target.emplace(ref.mesh, def.anchor, per_task);
  };
  std::future<void> ref_task =
      std::async(concurrent ? std::launch::async : std::launch::deferred, prepare_ref);
  {
    // A running reference task is waited for even when this side throws (it writes into `ref`).
    struct Join {
      std::future<void>& task;
      bool running;
      ~Join() {
        if (running && task.valid()) task.wait();
      }
    } join{ref_task, concurrent};
    dist = prepare(distorted, "distorted mesh", run, def, per_task);
    if (match_early) dist_target.emplace(dist.mesh, def.anchor, per_task);
  }
  ref_task.get();
  if (run.inputs_done) run.inputs_done();  // both meshes detached: the inputs are not read below
  MetricResult result;
  for (const auto* m : {&ref.mesh, &dist.mesh}) {
    result.warnings.insert(result.warnings.end(), m->warnings.begin(), m->warnings.end());
  }
  CurvatureCache curvatures(def.curvature, both && ref.box_size == dist.box_size, threads);
  std::optional<SurfaceMatches> d2r_matches, r2d_matches;
  if (match_early) {
    progress.begin("closest points, both directions", 2);
    auto matches = match_to_surfaces(
        {{dist.mesh.positions, &*ref_target}, {ref.mesh.positions, &*dist_target}}, threads);
    ref_target.reset();
    dist_target.reset();
    d2r_matches = std::move(matches[0]);
    r2d_matches = std::move(matches[1]);
  }
  if (run.direction != Direction::kRefToDist) {
    result.dist_to_ref = run_direction(dist, ref, def, run.scales, threads, curvatures, pool,
                                       std::move(d2r_matches), "dist→ref", progress);
  }
  if (run.direction != Direction::kDistToRef) {
    result.ref_to_dist = run_direction(ref, dist, def, run.scales, threads, curvatures, pool,
                                       std::move(r2d_matches), "ref→dist", progress);
  }
  combine_directions(result);
  progress.finish();
  return result;
}

}  // namespace qm3d::mesh::detail
