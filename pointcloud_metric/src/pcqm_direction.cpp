// One direction of PCQM (SPEC-PCQM 1.4 and 1.5). Points are processed in the order of the
// iterated cloud's k-d tree, which is spatially coherent: consecutive queries touch the same tree
// nodes and, in stage 2, neighbours' stage-1 values lie close together in memory. Results are
// written per point and summed later in input order, so any thread count gives the same bits.
// Names: `iterated` is the cloud whose points are visited, `other` the one they are matched on;
// comments use the spec's R (iterated) and D (other), which they are in the reference's direction.
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

#include "candidate_set.h"
#include "kd_tree.h"
#include "pcqm_internal.h"
#include "qm3d/common/large_arrays.h"
#include "qm3d/common/pooling.h"
#include "qm3d/common/statistics.h"
#include "quadric_fit.h"

namespace qm3d::pointcloud::detail {
namespace {

/// Points per query batch (consecutive k-d tree leaves searched with one candidate gather), and
/// how far a batch's box may grow when a leaf joins it: at most kBatchGrowth times the larger
/// side of the two boxes. Consecutive leaves are usually neighbours, but where the tree order
/// crosses a split plane high in the tree the next leaf can lie across the cloud: merged
/// regardless (the previous rule), a few batches had boxes of tens of thousands of candidates,
/// filtered by every one of their points. With the growth bound, batches of up to 32 points
/// (16.8 on average) had half the candidates per point of 16-point greedy batches (12.7), and the
/// gathers and filters took about 30% less time on the 1M sphere. Batches only decide how much
/// is searched: every list is exact, so they never change a value.
constexpr std::uint32_t kBatchPoints = 32;
constexpr double kBatchGrowth = 2.0;
/// Query batches per dynamic-schedule chunk: large enough to keep a thread's queries spatially
/// coherent, small enough to balance clouds of uneven density.
constexpr std::int64_t kBatchesPerChunk = 16;
/// Iterations ahead at which TreeColours announces its random reads of the input colours.
constexpr std::int64_t kColourPrefetch = 16;
/// Relative slack on the kNN reach of a batch, covering the rounding of its computation.
constexpr double kReachSlack = 1.0 + 1e-9;

int thread_count(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

struct Radii {
  double curvature2;   ///< r^2, passed as `radius * radius` (main.cpp)
  double statistics2;  ///< (rx r)^2, passed as `std::pow(rx r, 2.0)` (compute_statistics)
  double sigma;        ///< rx r / 2 (`debug_variance`)
};

Radii radii_of(const DirectionParams& p) {
  const double r = p.radius_rel * p.max_dim;
  const double stat = r * p.radius_factor;
  return Radii{r * r, std::pow(stat, 2.0), stat / 2.0};
}

/// `compute_distance` of main.cpp.
double point_distance(const Vec3& a, const Vec3& b) {
  return std::sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                   (b[2] - a[2]) * (b[2] - a[2]));
}

/// Stage-1 values of each point of the iterated cloud, in its tree order. Stage 1 writes every
/// element (in parallel: no serial zeroing pass), `underdetermined` by bits, and `correspondence`
/// only where it is not the point itself unless the diagnostics want them all (correspondence_of
/// reads it): on a colour-only distortion none is written, and its 24 bytes per point are never
/// faulted in.
struct PointData {
  explicit PointData(std::size_t n, bool diagnostics) : all_correspondences(diagnostics) {
    correspondence.resize(n);
    correspondence_is_point.resize(n);
    for (auto* v : {&curvature_iterated, &curvature_other, &lightness_iterated, &lightness_other,
                    &chroma_iterated, &chroma_other, &hue_difference}) {
      v->resize(n);
    }
    underdetermined.resize(n, 0);
    if (diagnostics) {
      lab_iterated.resize(n);
      lab_other.resize(n);
      count_radius_other.resize(n);
      count_radius_iterated.resize(n);
    }
  }
  bool all_correspondences;
  LargeArray<Vec3> correspondence;
  LargeArray<std::uint8_t> correspondence_is_point;  ///< p-hat == p (compared with ==)
  LargeArray<double> curvature_iterated, curvature_other;
  LargeArray<double> lightness_iterated, lightness_other, chroma_iterated, chroma_other,
      hue_difference;
  /// Which of p's quadric fits are underdetermined (quadric_fit.h): kCurvatureFit, kMatchFit.
  LargeArray<std::uint8_t> underdetermined;
  std::vector<Lab> lab_iterated, lab_other;                              // diagnostics only
  std::vector<std::uint32_t> count_radius_other, count_radius_iterated;  // diagnostics only
};

/// A cloud's colours in its k-d tree's order, so that stage 1 reads them where it reads the
/// points. Stored as 8-bit channels when every channel is some k / 255.0 (what the readers make
/// of 8-bit files: 3 instead of 24 bytes per point), else as given; operator[] gives back the
/// very doubles of the input either way (a -0.0 channel as +0.0, which srgb_to_linear maps
/// alike).
class TreeColours {
 public:
  /// Gathers in parallel (`threads` as DirectionParams::threads); every element is written
  /// on its own, so the copy does not depend on the thread count.
  TreeColours(const std::vector<Rgb>& colors, const KdTree& tree, int threads) {
    const std::vector<std::uint32_t>& order = tree.input_index();
    const auto n = static_cast<std::int64_t>(order.size());
    bytes_.resize(order.size());
    bool all_bytes = true;
#pragma omp parallel for num_threads(thread_count(threads)) reduction(&& : all_bytes)
    for (std::int64_t i = 0; i < n; ++i) {
      // Random reads of a 24 MB array: announced a few iterations ahead.
      if (i + kColourPrefetch < n)
        __builtin_prefetch(&colors[order[std::size_t(i + kColourPrefetch)]]);
      all_bytes = to_bytes(colors[order[std::size_t(i)]], bytes_[std::size_t(i)]) && all_bytes;
    }
    if (all_bytes) return;
    LargeArray<std::array<std::uint8_t, 3>>().swap(bytes_);
    exact_.resize(order.size());
#pragma omp parallel for num_threads(thread_count(threads))
    for (std::int64_t j = 0; j < n; ++j) exact_[std::size_t(j)] = colors[order[std::size_t(j)]];
  }
  Rgb operator[](std::size_t i) const {
    if (!exact_.empty()) return exact_[i];
    const auto& b = bytes_[i];
    const auto& unit = unit_values();
    return Rgb{unit[b[0]], unit[b[1]], unit[b[2]]};
  }

 private:
  /// k / 255.0 for every byte k (the division each lookup would make).
  static const std::array<double, 256>& unit_values() {
    static const std::array<double, 256> values = [] {
      std::array<double, 256> v{};
      for (int k = 0; k < 256; ++k) v[std::size_t(k)] = k / 255.0;
      return v;
    }();
    return values;
  }
  static bool to_bytes(const Rgb& c, std::array<std::uint8_t, 3>& out) {
    const double channels[3] = {c.r, c.g, c.b};
    const auto& unit = unit_values();
    for (int k = 0; k < 3; ++k) {
      if (!(channels[k] >= 0.0 && channels[k] <= 1.0)) return false;
      const int v = static_cast<int>(channels[k] * 255.0 + 0.5);
      if (unit[std::size_t(v)] != channels[k]) return false;
      out[k] = static_cast<std::uint8_t>(v);
    }
    return true;
  }
  LargeArray<std::array<std::uint8_t, 3>> bytes_;
  LargeArray<Rgb> exact_;
};

/// The two clouds' trees and colours; indices are tree indices. When both clouds have the same
/// positions in the same order (a colour-only distortion) they share one tree.
struct Clouds {
  const KdTree& iterated_tree;
  const KdTree& other_tree;
  bool same_positions;
  /// Stage 1 only (freed before stage 2).
  const TreeColours* iterated_colours = nullptr;
  const TreeColours* other_colours = nullptr;
};

struct Stage1Scratch {
  CandidateSet near_other;     ///< D's points within r of the batch's box
  CandidateSet reach_other;    ///< D's points within the batch's kNN reach (gathered when needed)
  CandidateSet near_iterated;  ///< R's points within r of the batch's box (when positions differ)
  bool have_reach = false;
  /// The last list of D (of R) had equal distances: search the next one in the reference's
  /// order directly (on voxelised clouds nearly every list has ties).
  bool ties_other = false, ties_iterated = false;
  std::vector<Neighbour> nearest, within_other, within_iterated;
  QuadricFitter fitter;
  // The last query whose kNN was computed and its k-th nearest distance on D: they bound the
  // next query's k-th distance by the triangle inequality, d_k(q) <= d_k(prev) + |q - prev|.
  Vec3 previous{0, 0, 0};
  double previous_kth = 0;
};

bool same_coordinates(const std::vector<Vec3>& a_points, const std::vector<Neighbour>& a,
                      const std::vector<Vec3>& b_points, const std::vector<Neighbour>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a_points[a[i].index] != b_points[b[i].index]) return false;
  }
  return true;
}

/// k_D and k_R: |H| maxDim of the quadrics fitted to D's and R's points within r of p, both
/// lists sorted by distance. The fit is a pure function of the neighbour coordinates, so when
/// both lists hold the same coordinates (unchanged geometry) it is computed once.
void curvatures(std::size_t i, const Clouds& c, const DirectionParams& params,
                const std::vector<Neighbour>& within_other,
                const std::vector<Neighbour>& within_iterated, QuadricFitter& fitter,
                PointData& out) {
  const Vec3& p = c.iterated_tree.points()[i];
  const QuadricFit on_other = fitter.fit(p, c.other_tree.points(), within_other);
  const QuadricFit on_iterated = same_coordinates(c.other_tree.points(), within_other,
                                                  c.iterated_tree.points(), within_iterated)
                                     ? on_other
                                     : fitter.fit(p, c.iterated_tree.points(), within_iterated);
  out.curvature_other[i] = std::abs(on_other.mean_curvature) * params.max_dim;
  out.curvature_iterated[i] = std::abs(on_iterated.mean_curvature) * params.max_dim;
  if (on_other.underdetermined || on_iterated.underdetermined) {
    out.underdetermined[i] |= kCurvatureFit;
  }
}

/// LAB2000HL of p's colour and of nn_D(p)'s colour, chroma, and the hue difference.
void colours(std::size_t i, std::uint32_t nearest, const Clouds& c, const Lab2000hlTable& table,
             PointData& out) {
  const Lab own = table.from_srgb((*c.iterated_colours)[i]);
  const Lab matched = table.from_srgb((*c.other_colours)[nearest]);
  out.lightness_iterated[i] = own.L;
  out.lightness_other[i] = matched.L;
  const double own_chroma = chroma(own), matched_chroma = chroma(matched);
  out.chroma_iterated[i] = own_chroma;
  out.chroma_other[i] = matched_chroma;
  out.hue_difference[i] = hue_difference(own, matched, own_chroma, matched_chroma);
  if (!out.lab_iterated.empty()) {
    out.lab_iterated[i] = own;
    out.lab_other[i] = matched;
  }
}

/// Gathers D's points within the kNN reach of the batch: d_k(q) <= d_k(p0) + |q - p0| for the
/// batch's first point p0. Also starts the chain of kNN bounds at p0.
void gather_reach(const std::array<std::uint32_t, 2>& batch, const Clouds& c, std::size_t k,
                  Stage1Scratch& s) {
  const std::vector<Vec3>& points = c.iterated_tree.points();
  const Vec3& p0 = points[batch[0]];
  c.other_tree.knn_search(p0, k, s.nearest);
  double spread2 = 0;
  for (std::uint32_t i = batch[0] + 1; i < batch[1]; ++i) {
    spread2 = std::max(spread2, squared_distance(p0, points[i]));
  }
  s.previous = p0;
  s.previous_kth = std::sqrt(s.nearest.back().distance2);
  const double reach = (s.previous_kth + std::sqrt(spread2)) * kReachSlack;
  s.reach_other.gather(c.other_tree, box_of(points, batch[0], batch[1]), reach * reach);
  s.have_reach = true;
}

/// The points of `tree` strictly within sqrt(radius2) of p, sorted by distance as the reference
/// sorts them (std::sort of its traversal order). The batched search gives the same list
/// whenever no two distances are equal; otherwise the order of the ties is the reference's to
/// decide, and the list is searched again in its order. `ties` carries over to the next query.
void sorted_within(const KdTree& tree, CandidateSet& near, const Vec3& p, double radius2,
                   bool& ties, std::vector<Neighbour>& out) {
  if (!ties) {
    near.radius(p, radius2, out);
    sort_by_distance(out);
    if (!has_ties(out)) return;
  }
  tree.sorted_radius_search(p, radius2, out);
  ties = has_ties(out);
}

/// nn_D(p) (returned, a D tree index), D's points within r of p (s.within_other, sorted) and
/// p-hat (SPEC-PCQM 1.4 step 3): the foot point of the quadric fitted to p's kNN on D when it is
/// not farther from p than nn_D(p), else nn_D(p). When a point of D coincides with p, it is
/// nn_D(p) and the foot point can only tie with it at distance 0: no kNN, no fit.
///
/// Where equal distances make the reference's choice depend on its traversal (SPEC-PCQM §9: the
/// first kNN result gives the colour, the k-th place goes to the tie reached first), the kNN is
/// searched in the reference's order.
std::uint32_t match(const std::array<std::uint32_t, 2>& batch, std::size_t i, const Clouds& c,
                    const DirectionParams& params, const Radii& radii, Stage1Scratch& s,
                    Vec3& correspondence, std::uint8_t& underdetermined) {
  const Vec3& p = c.iterated_tree.points()[i];
  const std::vector<Vec3>& other_points = c.other_tree.points();
  sorted_within(c.other_tree, s.near_other, p, radii.curvature2, s.ties_other, s.within_other);
  if (!s.within_other.empty() && s.within_other.front().distance2 == 0) {
    std::uint32_t nearest = s.within_other.front().index;
    if (s.within_other.size() > 1 && s.within_other[1].distance2 == 0) {
      c.other_tree.knn_search(p, 1, s.nearest);  // several points coincide with p
      nearest = s.nearest.front().index;
    }
    correspondence = other_points[nearest];
    return nearest;
  }
  if (s.ties_other) {
    c.other_tree.knn_search(p, params.knn, s.nearest);
  } else {
    if (!s.have_reach) gather_reach(batch, c, params.knn, s);
    const double bound =
        (s.previous_kth + std::sqrt(squared_distance(p, s.previous))) * kReachSlack;
    const CandidateSet::Knn found = s.reach_other.knn(p, params.knn, bound * bound, s.nearest);
    s.previous_kth = std::sqrt(found.kth_distance2);
    s.previous = p;
    if (found.tie_at_kth || has_ties(s.nearest)) c.other_tree.knn_search(p, params.knn, s.nearest);
  }
  const Vec3& closest = other_points[s.nearest.front().index];
  const QuadricFit fit = s.fitter.fit(p, other_points, s.nearest);
  if (fit.underdetermined) underdetermined |= kMatchFit;
  correspondence = point_distance(p, fit.foot) <= point_distance(p, closest) ? fit.foot : closest;
  return s.nearest.front().index;
}

void stage1_point(const std::array<std::uint32_t, 2>& batch, std::size_t i, const Clouds& c,
                  const DirectionParams& params, const Radii& radii, const Lab2000hlTable& table,
                  Stage1Scratch& s, PointData& out) {
  const Vec3& p = c.iterated_tree.points()[i];
  Vec3 correspondence;
  const std::uint32_t nearest =
      match(batch, i, c, params, radii, s, correspondence, out.underdetermined[i]);
  const bool is_point = correspondence == p;
  out.correspondence_is_point[i] = is_point;
  if (!is_point || out.all_correspondences) out.correspondence[i] = correspondence;
  const std::vector<Neighbour>& within_iterated =
      c.same_positions ? s.within_other : s.within_iterated;
  if (!c.same_positions) {
    sorted_within(c.iterated_tree, s.near_iterated, p, radii.curvature2, s.ties_iterated,
                  s.within_iterated);
  }
  if (!out.count_radius_other.empty()) {
    out.count_radius_other[i] = static_cast<std::uint32_t>(s.within_other.size());
    out.count_radius_iterated[i] = static_cast<std::uint32_t>(within_iterated.size());
  }
  curvatures(i, c, params, s.within_other, within_iterated, s.fitter, out);
  colours(i, nearest, c, table, out);
}

void stage1_batch(const std::array<std::uint32_t, 2>& batch, const Clouds& c,
                  const DirectionParams& params, const Radii& radii, const Lab2000hlTable& table,
                  Stage1Scratch& s, PointData& out) {
  const Box box = box_of(c.iterated_tree.points(), batch[0], batch[1]);
  s.near_other.gather(c.other_tree, box, radii.curvature2);
  s.have_reach = false;
  if (!c.same_positions) s.near_iterated.gather(c.iterated_tree, box, radii.curvature2);
  for (std::uint32_t i = batch[0]; i < batch[1]; ++i) {
    stage1_point(batch, i, c, params, radii, table, s, out);
  }
}

/// Largest side of a box.
double longest_side(const Box& b) {
  return std::max(b.hi[0] - b.lo[0], std::max(b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]));
}

Box merged(const Box& a, const Box& b) {
  Box m = a;
  for (int k = 0; k < 3; ++k) {
    m.lo[k] = std::min(a.lo[k], b.lo[k]);
    m.hi[k] = std::max(a.hi[k], b.hi[k]);
  }
  return m;
}

/// Consecutive leaves of `tree` merged into query batches of at most kBatchPoints points whose
/// box grows by at most kBatchGrowth with each leaf (a leaf holds at most 10 points, often 5 or
/// 6): one candidate gather then serves a dozen or more neighbouring queries. Tree-index ranges
/// [first, last), in tree order.
std::vector<std::array<std::uint32_t, 2>> query_batches(const KdTree& tree) {
  std::vector<std::array<std::uint32_t, 2>> batches;
  Box box;  // of the last batch
  for (const auto& leaf : tree.leaves()) {
    const Box leaf_box = box_of(tree.points(), leaf[0], leaf[1]);
    if (!batches.empty() && leaf[1] - batches.back()[0] <= kBatchPoints) {
      const Box both = merged(box, leaf_box);
      if (longest_side(both) <=
          kBatchGrowth * std::max(longest_side(box), longest_side(leaf_box))) {
        batches.back()[1] = leaf[1];
        box = both;
        continue;
      }
    }
    batches.push_back(leaf);
    box = leaf_box;
  }
  return batches;
}

// Calls visit(batch, scratch) for every query batch of `tree`, in parallel, with one Scratch
// per thread; reports the points done to `progress` (may be null).
template <typename Scratch, typename Visit>
void for_each_batch(const KdTree& tree, int threads, ProgressSteps* progress, Visit&& visit) {
  const auto batches = query_batches(tree);
  const auto n = static_cast<std::int64_t>(batches.size());
  LoopProgress done(progress, tree.size());
#pragma omp parallel num_threads(thread_count(threads))
  {
    Scratch scratch;
#pragma omp for schedule(dynamic, kBatchesPerChunk)
    for (std::int64_t b = 0; b < n; ++b) {
      const auto& batch = batches[std::size_t(b)];
      visit(batch, scratch);
      done.add(batch[1] - batch[0]);
    }
  }
  done.finish();
}

PointData stage1(const Clouds& c, const DirectionParams& params, const Radii& radii,
                 const Lab2000hlTable& table) {
  PointData out(c.iterated_tree.size(), params.diagnostics);
  for_each_batch<Stage1Scratch>(c.iterated_tree, params.threads, params.progress,
                                [&](const auto& batch, auto& scratch) {
                                  stage1_batch(batch, c, params, radii, table, scratch, out);
                                });
  return out;
}

struct Stage2Scratch {
  CandidateSet candidates;
  CandidateSet::Selection within;  ///< p's statistics neighbourhood, held by `candidates`
  NeighbourhoodSamples samples;
};

/// p-hat of the point of tree index i: the point itself or the stored correspondence (PointData).
/// Where `==` found them equal they differ at most in the sign of a zero, which no distance
/// sees.
const Vec3& correspondence_of(const PointData& d, const KdTree& tree, std::size_t i) {
  return d.correspondence_is_point[i] != 0 ? tree.points()[i] : d.correspondence[i];
}

/// Paired samples of p's statistics neighbourhood N(p) (R's points within rx r): w1 from
/// |p - q_j|, w2 from |p-hat - q-hat_j| (equal to w1 when both correspondences are the points
/// themselves); R side = index 1, D side = index 2 (compute_statistics).
void gather_samples(std::size_t i, const KdTree& tree, const PointData& d, const Radii& radii,
                    Stage2Scratch& s) {
  NeighbourhoodSamples& out = s.samples;
  const std::size_t n = s.within.size();
  for (auto* v : {&out.w1, &out.w2, &out.curv1, &out.curv2, &out.light1, &out.light2, &out.chroma1,
                  &out.chroma2, &out.hue_diff}) {
    v->resize(n);
  }
  const bool i_is_point = d.correspondence_is_point[i] != 0;
  // Distances first, then the weights in one vectorised pass per side; w2 is w1 wherever both
  // correspondences are the points themselves (the same distance, so the same weight).
  bool w2_is_w1 = i_is_point;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t j = s.within[k].index;
    const double d1 = std::sqrt(s.within[k].distance2);
    const bool same = i_is_point && d.correspondence_is_point[j] != 0;
    w2_is_w1 = w2_is_w1 && same;
    out.w1[k] = d1;
    out.w2[k] =
        same ? d1 : point_distance(correspondence_of(d, tree, i), correspondence_of(d, tree, j));
    out.curv1[k] = d.curvature_iterated[j];
    out.curv2[k] = d.curvature_other[j];
    out.light1[k] = d.lightness_iterated[j];
    out.light2[k] = d.lightness_other[j];
    out.chroma1[k] = d.chroma_iterated[j];
    out.chroma2[k] = d.chroma_other[j];
    out.hue_diff[k] = d.hue_difference[j];
  }
  gaussian_weights_in_place(out.w1.data(), n, radii.sigma);
  if (w2_is_w1) {
    out.w2 = out.w1;
  } else {
    gaussian_weights_in_place(out.w2.data(), n, radii.sigma);
  }
}

/// f1..f3 and s4..s8 (similarities, pooled as the reference pools them) of the points of one
/// batch, stored at their input indices.
void stage2_batch(const std::array<std::uint32_t, 2>& batch, const KdTree& iterated_tree,
                  const PointData& d, const Radii& radii, Stage2Scratch& s,
                  LargeArray<FeatureVector>& features, std::vector<std::uint32_t>* counts) {
  // Features are stored in input order (a cache miss per point): announced before the work.
  for (std::uint32_t i = batch[0]; i < batch[1]; ++i) {
    const FeatureVector& f = features[iterated_tree.input_index()[i]];
    __builtin_prefetch(&f.front(), 1);
    __builtin_prefetch(&f.back(), 1);
  }
  s.candidates.gather(iterated_tree, box_of(iterated_tree.points(), batch[0], batch[1]),
                      radii.statistics2);
  for (std::uint32_t i = batch[0]; i < batch[1]; ++i) {
    s.within = s.candidates.radius(iterated_tree.points()[i], radii.statistics2);
    gather_samples(i, iterated_tree, d, radii, s);
    const std::uint32_t input = iterated_tree.input_index()[i];
    features[input] = local_features_and_similarities(s.samples, kPcqmConventions);
    if (counts != nullptr) (*counts)[input] = static_cast<std::uint32_t>(s.within.size());
  }
}

LargeArray<FeatureVector> stage2(const KdTree& iterated_tree, const PointData& d,
                                 const DirectionParams& params, const Radii& radii,
                                 std::vector<std::uint32_t>* counts) {
  LargeArray<FeatureVector> features(iterated_tree.size());  // each written by stage 2
  for_each_batch<Stage2Scratch>(
      iterated_tree, params.threads, params.progress, [&](const auto& batch, auto& scratch) {
        stage2_batch(batch, iterated_tree, d, radii, scratch, features, counts);
      });
  return features;
}

template <typename Array>
std::vector<typename Array::value_type> to_input_order(const Array& tree_order,
                                                       const KdTree& tree) {
  std::vector<typename Array::value_type> out(tree_order.size());
  for (std::size_t i = 0; i < tree_order.size(); ++i) out[tree.input_index()[i]] = tree_order[i];
  return out;
}

/// Share of a sample of the iterated points (about kSamples, evenly spread in tree order) for
/// which `underdetermined(p)` holds.
template <typename Test>
double sampled_share(const KdTree& tree, Test&& underdetermined) {
  constexpr std::size_t kSamples = 1000;
  const std::size_t step = std::max<std::size_t>(1, tree.size() / kSamples);
  std::size_t sampled = 0;
  std::size_t hits = 0;
  for (std::size_t i = 0; i < tree.size(); i += step, ++sampled) {
    hits += underdetermined(tree.points()[i]) ? 1 : 0;
  }
  return double(hits) / double(sampled);
}

/// Settings that would leave at most half of kUnderdeterminedShare of the points with an
/// underdetermined fit of each kind that is too common (bits of `kinds`), measured on a sample:
/// the smallest curvature radius_rel and the smallest knn on a geometric scale above the current
/// ones (up to 16 times them); 0 where none does.
Suggestion suggest_settings(const Clouds& c, const DirectionParams& params, std::uint8_t kinds) {
  constexpr double kTarget = kUnderdeterminedShare / 2;
  constexpr double kMaxGrowth = 16;
  QuadricFitter fitter;
  std::vector<Neighbour> found;
  Suggestion out;
  if (kinds & kCurvatureFit) {
    for (double rel = params.radius_rel * 1.25; rel <= params.radius_rel * kMaxGrowth;
         rel *= 1.25) {
      const double r = rel * params.max_dim;
      const double share = sampled_share(c.iterated_tree, [&](const Vec3& p) {
        for (const KdTree* tree : {&c.other_tree, &c.iterated_tree}) {
          tree->sorted_radius_search(p, r * r, found);
          if (fitter.fit(p, tree->points(), found).underdetermined) return true;
        }
        return false;
      });
      if (share <= kTarget) {
        out.radius_rel = rel;
        break;
      }
    }
  }
  if (kinds & kMatchFit) {
    for (std::size_t k = params.knn + (params.knn + 1) / 2;
         k <= params.knn * kMaxGrowth && k <= c.other_tree.size(); k += (k + 1) / 2) {
      const double share = sampled_share(c.iterated_tree, [&](const Vec3& p) {
        c.other_tree.knn_search(p, k, found);
        // A point of D on p is its correspondence: no fit (match()).
        return found.front().distance2 != 0 &&
               fitter.fit(p, c.other_tree.points(), found).underdetermined;
      });
      if (share <= kTarget) {
        out.knn = k;
        break;
      }
    }
  }
  return out;
}

PointDiagnostics diagnostics_of(const PointData& d, const KdTree& tree) {
  PointDiagnostics out;
  out.correspondence = to_input_order(d.correspondence, tree);
  out.curvature_iterated = to_input_order(d.curvature_iterated, tree);
  out.curvature_other = to_input_order(d.curvature_other, tree);
  out.lab_iterated = to_input_order(d.lab_iterated, tree);
  out.lab_other = to_input_order(d.lab_other, tree);
  out.chroma_iterated = to_input_order(d.chroma_iterated, tree);
  out.chroma_other = to_input_order(d.chroma_other, tree);
  out.hue_difference = to_input_order(d.hue_difference, tree);
  out.count_radius_other = to_input_order(d.count_radius_other, tree);
  out.count_radius_iterated = to_input_order(d.count_radius_iterated, tree);
  out.underdetermined = to_input_order(d.underdetermined, tree);
  return out;
}

}  // namespace

double reference_max_dim(const std::vector<Vec3>& positions) {
  // PointSet.h initialises min to DBL_MAX and max to numeric_limits<double>::min() = +2.2e-308.
  Vec3 lo;
  Vec3 hi;
  lo.fill(std::numeric_limits<double>::max());
  hi.fill(std::numeric_limits<double>::min());
  for (const Vec3& p : positions) {
    for (int a = 0; a < 3; ++a) {
      hi[a] = hi[a] > p[a] ? hi[a] : p[a];
      lo[a] = lo[a] < p[a] ? lo[a] : p[a];
    }
  }
  // main.cpp: rangeX = |xmin| + |xmax|, maxDim = max(rangeX, max(rangeY, rangeZ)).
  const double x = std::abs(lo[0]) + std::abs(hi[0]);
  const double y = std::abs(lo[1]) + std::abs(hi[1]);
  const double z = std::abs(lo[2]) + std::abs(hi[2]);
  return std::max(x, std::max(y, z));
}

DirectionOutput compute_direction(const ColoredCloud& iterated, const ColoredCloud& other,
                                  const DirectionParams& params, const Lab2000hlTable& table) {
  const auto stage = [&](const char* what) {
    if (params.progress) params.progress->begin(params.label + ": " + what);
  };
  stage("search trees");
  const bool same_positions = iterated.positions == other.positions;
  const KdTree iterated_tree(iterated.positions, params.threads);
  std::optional<KdTree> own_other_tree;
  if (!same_positions) own_other_tree.emplace(other.positions, params.threads);
  const KdTree& other_tree = same_positions ? iterated_tree : *own_other_tree;
  DirectionParams p = params;
  p.knn = std::min(params.knn, other_tree.size());
  const Radii radii = radii_of(p);
  Clouds clouds{iterated_tree, other_tree, same_positions};

  stage("curvatures and correspondences");
  PointData data = [&] {
    const TreeColours iterated_colours(iterated.colors, iterated_tree, params.threads);
    const TreeColours other_colours(other.colors, other_tree, params.threads);
    if (params.inputs_done) params.inputs_done();  // `iterated` and `other` are not read below
    clouds.iterated_colours = &iterated_colours;
    clouds.other_colours = &other_colours;
    PointData d = stage1(clouds, p, radii, table);
    clouds.iterated_colours = clouds.other_colours = nullptr;
    return d;
  }();
  DirectionOutput out;
  std::vector<std::uint32_t> counts;
  if (p.diagnostics) counts.resize(iterated_tree.size());
  stage("features");
  out.features = stage2(iterated_tree, data, p, radii, p.diagnostics ? &counts : nullptr);
  out.pooled = mean_features_from_similarities(out.features.data(), out.features.size());
  std::uint8_t too_common = 0;
  for (std::uint8_t kind : {kCurvatureFit, kMatchFit}) {
    std::size_t& count =
        kind == kCurvatureFit ? out.underdetermined_curvature : out.underdetermined_match;
    for (std::uint8_t u : data.underdetermined) count += (u & kind) != 0;
    if (count > kUnderdeterminedShare * double(iterated_tree.size())) too_common |= kind;
  }
  if (too_common != 0) out.suggestion = suggest_settings(clouds, p, too_common);
  const auto n = static_cast<std::int64_t>(out.features.size());
#pragma omp parallel for num_threads(thread_count(p.threads))
  for (std::int64_t i = 0; i < n; ++i) similarities_to_features(out.features[std::size_t(i)]);
  if (p.diagnostics) {
    out.diagnostics = diagnostics_of(data, iterated_tree);
    out.diagnostics.count_statistics = std::move(counts);
  }
  return out;
}

}  // namespace qm3d::pointcloud::detail
