#include "qm3d/mesh/cmdm.h"

#include <cmath>
#include <deque>
#include <future>
#include <stdexcept>

#include "curvature.h"
#include "halfedge_mesh.h"
#include "neighbourhood.h"
#include "projection.h"
#include "qm3d/common/color.h"
#include "qm3d/common/error.h"

namespace qm3d::mesh {
namespace {

using detail::HalfedgeMesh;

// MEPP2 process_CMDM_multires: rc starts at 0.001 and grows by 0.0005 per scale; the
// neighbourhood radius is 3 rc BB and the Gaussian sigma a third of it.
constexpr double kFirstCurvatureRadius = 0.001;
constexpr double kCurvatureRadiusStep = 0.0005;
constexpr double kNeighbourhoodFactor = 3.0;

void validate(const CmdmOptions& o) {
  if (o.scales < 1 || o.scales > 100) {
    throw std::invalid_argument("CMDM: the number of scales must be between 1 and 100");
  }
}

double longest_side(const HalfedgeMesh& m, const std::string& name) {
  const double bb = bounding_box(m.positions.begin(), m.positions.end()).longest_side();
  if (!(bb > 0) || !std::isfinite(bb)) {
    throw NumericError(name + ": bounding box has zero size (all vertices identical)");
  }
  return bb;
}

// Values of the second mesh interpolated at each matched point.
std::vector<double> interpolate_all(const std::vector<detail::SurfaceMatch>& matches,
                                    const HalfedgeMesh& second, const std::vector<double>& values) {
  std::vector<double> out(matches.size());
  for (std::size_t i = 0; i < matches.size(); ++i) {
    out[i] = detail::interpolate(matches[i], second.triangles[matches[i].face], values);
  }
  return out;
}

std::vector<Lab> interpolate_colors(const std::vector<detail::SurfaceMatch>& matches,
                                    const HalfedgeMesh& second, const std::vector<Lab>& colors) {
  std::vector<double> channel(colors.size());
  std::vector<Lab> out(matches.size());
  for (double Lab::*c : {&Lab::L, &Lab::a, &Lab::b}) {
    for (std::size_t i = 0; i < colors.size(); ++i) channel[i] = colors[i].*c;
    const auto values = interpolate_all(matches, second, channel);
    for (std::size_t i = 0; i < out.size(); ++i) out[i].*c = values[i];
  }
  return out;
}

// Adds each vertex's features at one scale to the running sums.
void accumulate_scale(const detail::MatchedFields& fields, const detail::WalkParameters& walk,
                      std::vector<FeatureVector>& sums) {
  const auto n = static_cast<std::int64_t>(sums.size());
#pragma omp parallel
  {
    detail::WalkScratch scratch;
    NeighbourhoodSamples samples;
#pragma omp for schedule(dynamic, 512)
    for (std::int64_t v = 0; v < n; ++v) {
      detail::sample_neighbourhood(fields, static_cast<std::uint32_t>(v), walk, scratch, samples);
      const FeatureVector f = local_features(samples, kCmdmConventions);
      for (std::size_t k = 0; k < kNumFeatures; ++k) sums[v][k] += f[k];
    }
  }
}

// LAB2000HL colour of each vertex of the metric's mesh (duplicated vertices share the input's).
std::vector<Lab> vertex_lab2000hl(const HalfedgeMesh& m, const ColoredMesh& input,
                                  const Lab2000hlTable& table) {
  if (input.colors.size() != input.positions.size()) {
    throw FormatError("mesh has " + std::to_string(input.colors.size()) + " colours for " +
                      std::to_string(input.positions.size()) + " vertices");
  }
  std::vector<Lab> lab = to_lab2000hl(input.colors, table);
  for (std::size_t v = lab.size(); v < m.input_vertex.size(); ++v) lab.push_back(lab[m.input_vertex[v]]);
  return lab;
}

// Pools the per-vertex sums over scales (MEPP2: sum over vertices / (n * scales), then weights).
void pool_direction(const std::vector<FeatureVector>& sums, std::size_t input_vertices,
                    const CmdmOptions& options, CmdmDirectionResult& result) {
  const double count = static_cast<double>(sums.size()) * options.scales;
  FeatureVector total{};
  for (const auto& s : sums) {
    for (std::size_t k = 0; k < kNumFeatures; ++k) total[k] += s[k];
  }
  for (std::size_t k = 0; k < kNumFeatures; ++k) result.features[k] = total[k] / count;
  result.score = options.model.apply(result.features);
  if (!options.per_vertex) return;
  // Duplicated (non-manifold) vertices come after the input's, so the first input_vertices
  // entries are the input's vertices in order.
  result.local_distortion.resize(input_vertices);
  for (std::size_t v = 0; v < input_vertices; ++v) {
    result.local_distortion[v] = options.model.apply(sums[v]) / options.scales;
  }
}

// Processed curvature of a mesh at one radius, remembered for the other direction when both
// directions use the same radii (same bounding-box size, e.g. colour-only distortions).
class CurvatureCache {
 public:
  explicit CurvatureCache(bool enabled) : enabled_(enabled) {}

  const std::vector<double>& get(const HalfedgeMesh& mesh, double radius, double maxdim) {
    for (const Entry& e : entries_) {
      if (e.mesh == &mesh && e.radius == radius && e.maxdim == maxdim) return e.values;
    }
    // Without reuse only the current scale's pair is kept (popping the front of a deque leaves
    // references to the other entries valid).
    if (!enabled_ && entries_.size() >= 2) entries_.pop_front();
    entries_.push_back({&mesh, radius, maxdim,
                        detail::processed_curvature(mesh, radius, maxdim,
                                                    detail::CurvatureVariant::kCmdm)});
    return entries_.back().values;
  }

 private:
  struct Entry {
    const HalfedgeMesh* mesh;
    double radius, maxdim;
    std::vector<double> values;
  };
  bool enabled_;
  std::deque<Entry> entries_;  // stable references while growing
};

// One direction: iterate `first`'s vertices, match them on `second` (SPEC-CMDM 1.4-1.9).
CmdmDirectionResult compute_direction(const HalfedgeMesh& first, const std::vector<Lab>& lab1,
                                      const HalfedgeMesh& second, const std::vector<Lab>& lab2,
                                      const CmdmOptions& options, double maxdim,
                                      std::size_t input_vertices, CurvatureCache& curvatures) {
  CmdmDirectionResult result;
  result.bbox_max_side = maxdim;
  auto [matched_point, matches] = detail::match_to_surface(first.positions, second,
                                                           detail::HeronAnchor::kProjectedPoint);
  const std::vector<Lab> lab_match = interpolate_colors(matches, second, lab2);

  std::vector<FeatureVector> sums(first.positions.size(), FeatureVector{});
  double rc = kFirstCurvatureRadius;
  for (int level = 0; level < options.scales; ++level) {
    const auto& curv1 = curvatures.get(first, maxdim * rc, maxdim);
    const auto curv_match = interpolate_all(matches, second, curvatures.get(second, maxdim * rc, maxdim));
    const detail::MatchedFields fields{&first, &matched_point, &curv1, &curv_match, &lab1, &lab_match};
    const double h = rc * kNeighbourhoodFactor * maxdim;
    accumulate_scale(fields, {h, h / 3, /*strict_outward_test=*/false}, sums);
    rc += kCurvatureRadiusStep;
  }
  pool_direction(sums, input_vertices, options, result);
  return result;
}

}  // namespace

CmdmResult compute_cmdm(const ColoredMesh& reference, const ColoredMesh& distorted,
                        const CmdmOptions& options) {
  validate(options);
  const auto table = Lab2000hlTable::shared(resolve_data_dir(options.data_dir));
  // The two meshes are prepared concurrently (CGAL's Surface_mesh construction is sequential).
  auto ref_task = std::async(std::launch::async, [&] {
    return detail::build_halfedge_mesh(reference, "reference mesh");
  });
  const HalfedgeMesh dist = detail::build_halfedge_mesh(distorted, "distorted mesh");
  const HalfedgeMesh ref = ref_task.get();
  const std::vector<Lab> lab_ref = vertex_lab2000hl(ref, reference, *table);
  const std::vector<Lab> lab_dist = vertex_lab2000hl(dist, distorted, *table);
  CmdmResult result;
  for (const auto* m : {&ref, &dist}) {
    result.warnings.insert(result.warnings.end(), m->warnings.begin(), m->warnings.end());
  }
  const bool both = options.direction == CmdmDirection::kSymmetric;
  const double bb_dist = longest_side(dist, "distorted mesh");
  const double bb_ref = longest_side(ref, "reference mesh");
  CurvatureCache curvatures(both && bb_dist == bb_ref);
  if (options.direction != CmdmDirection::kRefToDist) {
    result.dist_to_ref = compute_direction(dist, lab_dist, ref, lab_ref, options, bb_dist,
                                           distorted.positions.size(), curvatures);
  }
  if (options.direction != CmdmDirection::kDistToRef) {
    result.ref_to_dist = compute_direction(ref, lab_ref, dist, lab_dist, options, bb_ref,
                                           reference.positions.size(), curvatures);
  }
  if (result.dist_to_ref && result.ref_to_dist) {
    result.score = (result.dist_to_ref->score + result.ref_to_dist->score) / 2;
  } else {
    result.score = result.dist_to_ref ? result.dist_to_ref->score : result.ref_to_dist->score;
  }
  return result;
}

}  // namespace qm3d::mesh
