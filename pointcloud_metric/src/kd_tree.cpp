#include "kd_tree.h"

#include <omp.h>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

#include "qm3d/common/cpu.h"
#include "qm3d/common/large_arrays.h"

#if defined(__GNUC__) && defined(__x86_64__)
#define QM3D_KD_TREE_AVX2 1
#include <immintrin.h>
#endif

namespace qm3d::pointcloud::detail {
namespace {

/// Lists up to this size are insertion-sorted (about 20% faster than std::sort at 32 elements).
constexpr std::size_t kInsertionSortMax = 64;
/// Subtrees larger than this are built as separate OpenMP tasks.
constexpr std::size_t kTaskThreshold = 1 << 15;
/// box_search prunes a cell only when its lower-bound distance exceeds the bound by this factor,
/// so that rounding in the incremental bound can never drop a point the exact test would keep.
constexpr double kPruneSlack = 1.0 + 1e-9;
/// middleSplit_'s EPS: a dim qualifies when its span exceeds (1 - EPS) of the largest span.
constexpr double kSpanEps = 0.00001;

/// Room for the nodes of a (sub)tree over `points` points: leaves hold 6 to 7 points on
/// typical clouds (about points / 3 nodes); points / 2 covers them without regrowth, whose
/// copies would stay resident in the building thread's heap.
std::size_t expected_nodes(std::size_t points) { return points / 2 + 1; }

#if defined(QM3D_KD_TREE_AVX2)
/// Lists up to this size are sorted by counting ranks (quadratic, but branch-free: about twice
/// as fast as the insertion sort on PCQM's lists of 15 to 20 neighbours).
constexpr std::size_t kRankSortMax = 32;
static_assert(kRankSortMax < 64, "the placed ranks are bits of a 64-bit word");

// Sorts by (distance, index) by placing each entry at its rank, the number of entries
// NeighbourOrder puts before it, counted four at a time. That order is total on a list without
// NaN distances and repeated (distance, index) pairs, so the result is the one every correct sort
// gives; false (the list untouched) when the ranks are not a permutation (such a list).
__attribute__((target("avx2"))) bool sort_by_rank_avx2(std::vector<Neighbour>& v) {
  const std::size_t n = v.size();
  alignas(32) double d[kRankSortMax];
  alignas(32) double id[kRankSortMax];  // indices below 2^32: exact as doubles
  const std::size_t padded = (n + 3) / 4 * 4;
  for (std::size_t i = 0; i < n; ++i) {
    d[i] = v[i].distance2;
    id[i] = static_cast<double>(v[i].index);
  }
  // Padding is never before anything: +inf is not below any distance, and ties it only with
  // +inf, whose index is then not above the padding's +inf.
  for (std::size_t i = n; i < padded; ++i) d[i] = id[i] = std::numeric_limits<double>::infinity();
  Neighbour sorted[kRankSortMax];
  std::uint64_t placed = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const __m256d di = _mm256_set1_pd(d[i]);
    const __m256d ii = _mm256_set1_pd(id[i]);
    __m256i count = _mm256_setzero_si256();
    for (std::size_t j = 0; j < padded; j += 4) {
      const __m256d dj = _mm256_load_pd(d + j);
      const __m256d before =
          _mm256_or_pd(_mm256_cmp_pd(dj, di, _CMP_LT_OQ),
                       _mm256_and_pd(_mm256_cmp_pd(dj, di, _CMP_EQ_OQ),
                                     _mm256_cmp_pd(_mm256_load_pd(id + j), ii, _CMP_LT_OQ)));
      count = _mm256_sub_epi64(count, _mm256_castpd_si256(before));  // true lanes are -1
    }
    alignas(32) std::uint64_t lanes[4];
    _mm256_store_si256(reinterpret_cast<__m256i*>(lanes), count);
    const std::uint64_t rank = lanes[0] + lanes[1] + lanes[2] + lanes[3];
    if (rank >= n) return false;
    sorted[rank] = v[i];
    placed |= std::uint64_t{1} << rank;
  }
  if (placed != (std::uint64_t{1} << n) - 1) return false;
  std::copy(sorted, sorted + n, v.begin());
  return true;
}
#endif

}  // namespace

void sort_by_distance(std::vector<Neighbour>& neighbours) {
#if defined(QM3D_KD_TREE_AVX2)
  if (neighbours.size() > 1 && neighbours.size() <= kRankSortMax && cpu_has_avx2() &&
      sort_by_rank_avx2(neighbours)) {
    return;
  }
#endif
  const NeighbourOrder closer;
  if (neighbours.size() > kInsertionSortMax) {
    std::sort(neighbours.begin(), neighbours.end(), closer);
    return;
  }
  for (std::size_t i = 1; i < neighbours.size(); ++i) {
    const Neighbour x = neighbours[i];
    std::size_t j = i;
    for (; j > 0 && closer(x, neighbours[j - 1]); --j) neighbours[j] = neighbours[j - 1];
    neighbours[j] = x;
  }
}

bool has_ties(const std::vector<Neighbour>& sorted) {
  for (std::size_t i = 1; i < sorted.size(); ++i) {
    if (sorted[i].distance2 == sorted[i - 1].distance2) return true;
  }
  return false;
}

KdTree::KdTree(const std::vector<Vec3>& points, int threads) {
  if (points.size() >= std::numeric_limits<std::uint32_t>::max()) {
    throw std::length_error("k-d tree: too many points (" + std::to_string(points.size()) + ")");
  }
  if (points.empty()) return;
  // nanoflann's vind, initially the input order; computeBoundingBox: the tight box.
  std::vector<std::uint32_t> order;
  reserve_with_huge_pages(order, points.size());
  order.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
  for (int a = 0; a < 3; ++a) root_box_[a] = {points[0][a], points[0][a]};
  for (const Vec3& p : points) {
    for (int a = 0; a < 3; ++a) {
      if (p[a] < root_box_[a][0]) root_box_[a][0] = p[a];
      if (p[a] > root_box_[a][1]) root_box_[a][1] = p[a];
    }
  }
  // The points are permuted along with their indices (same swaps as nanoflann's vind): the
  // build reads them contiguously, and the result is the tree-order copy.
  reserve_with_huge_pages(points_, points.size());
  points_.assign(points.begin(), points.end());
  Bounds box = root_box_;
  nodes_.reserve(expected_nodes(points.size()));
#pragma omp parallel num_threads( \
    threads > 0 ? threads         \
                : omp_get_max_threads()) if (!omp_in_parallel() && points.size() > kTaskThreshold)
#pragma omp single
  build(order, 0, points.size(), box, nodes_);
  input_index_ = std::move(order);
  index_leaves();
}

void KdTree::index_leaves() {
  for (Node& node : nodes_) {  // pre-order: leaves come in tree order
    if (node.divfeat != kLeaf) continue;
    node.child2 = static_cast<std::uint32_t>(leaves_.size());
    leaves_.push_back({node.first, node.last});
    std::array<Vec3, 2> box{points_[node.first], points_[node.first]};
    for (std::uint32_t i = node.first + 1; i < node.last; ++i) {
      for (int a = 0; a < 3; ++a) {
        box[0][a] = std::min(box[0][a], points_[i][a]);
        box[1][a] = std::max(box[1][a], points_[i][a]);
      }
    }
    leaf_boxes_.push_back(box);
  }
}

// nanoflann 1.1.7 divideTree / middleSplit_ / planeSplit over order[left, right), appending the
// subtree to `out` in pre-order (first child = next node). On entry `box` is the inherited box;
// on return it is the tight box of the subtree's points.
void KdTree::build(std::vector<std::uint32_t>& order, std::size_t left, std::size_t right,
                   Bounds& box, std::vector<Node>& out) {
  const std::size_t self = out.size();
  out.emplace_back();
  Vec3* pts = points_.data() + left;  // order[left + i] is the input index of pts[i]
  const std::size_t count = right - left;
  if (count <= kLeafSize) {
    out[self].divfeat = kLeaf;
    out[self].first = static_cast<std::uint32_t>(left);
    out[self].last = static_cast<std::uint32_t>(right);
    for (int a = 0; a < 3; ++a) box[a] = {pts[0][a], pts[0][a]};
    for (std::size_t k = 1; k < count; ++k) {
      for (int a = 0; a < 3; ++a) {
        if (box[a][0] > pts[k][a]) box[a][0] = pts[k][a];
        if (box[a][1] < pts[k][a]) box[a][1] = pts[k][a];
      }
    }
    return;
  }
  std::uint32_t* ind = order.data() + left;
  std::array<std::array<double, 2>, 3> ranges{};
  std::array<bool, 3> have_range{};
  const auto min_max = [&](int axis) {  // computeMinMax, once per axis and node
    if (!have_range[axis]) {
      std::array<double, 2> r{pts[0][axis], pts[0][axis]};
      for (std::size_t i = 1; i < count; ++i) {
        const double v = pts[i][axis];
        if (v < r[0]) r[0] = v;
        if (v > r[1]) r[1] = v;
      }
      ranges[axis] = r;
      have_range[axis] = true;
    }
    return ranges[axis];
  };

  // middleSplit_: the spread is measured along the dim chosen so far, not along the candidate.
  double max_span = box[0][1] - box[0][0];
  for (int a = 1; a < 3; ++a) max_span = std::max(max_span, box[a][1] - box[a][0]);
  double max_spread = -1;
  int cut = 0;
  for (int a = 0; a < 3; ++a) {
    if (box[a][1] - box[a][0] > (1 - kSpanEps) * max_span) {
      const auto range = min_max(cut);
      const double spread = range[1] - range[0];
      if (spread > max_spread) {
        cut = a;
        max_spread = spread;
      }
    }
  }
  const double split_val = (box[cut][0] + box[cut][1]) / 2;
  const auto range = min_max(cut);
  const double cutval = split_val < range[0]   ? range[0]
                        : split_val > range[1] ? range[1]
                                               : split_val;

  // planeSplit: two Hoare passes, < cutval then <= cutval.
  const auto pass = [&](std::size_t l, auto goes_left) {
    std::size_t r = count - 1;
    for (;;) {
      while (l <= r && goes_left(pts[l][cut])) ++l;
      while (r != 0 && l <= r && !goes_left(pts[r][cut])) --r;
      if (l > r || r == 0) break;
      std::swap(ind[l], ind[r]);
      std::swap(pts[l], pts[r]);
      ++l;
      --r;
    }
    return l;
  };
  const std::size_t lim1 = pass(0, [cutval](double v) { return v < cutval; });
  const std::size_t lim2 = pass(lim1, [cutval](double v) { return v <= cutval; });
  const std::size_t idx = lim1 > count / 2 ? lim1 : lim2 < count / 2 ? lim2 : count / 2;

  Bounds left_box = box;
  left_box[cut][1] = cutval;
  Bounds right_box = box;
  right_box[cut][0] = cutval;
  std::size_t child2 = 0;
  if (count > kTaskThreshold && omp_in_parallel()) {
    std::vector<Node> second;
    second.reserve(expected_nodes(count - idx));
#pragma omp task default(shared)
    build(order, left + idx, right, right_box, second);
    build(order, left, left + idx, left_box, out);
#pragma omp taskwait
    child2 = out.size();
    for (Node n : second) {
      if (n.divfeat != kLeaf) n.child2 += static_cast<std::uint32_t>(child2);
      out.push_back(n);
    }
  } else {
    build(order, left, left + idx, left_box, out);
    child2 = out.size();
    build(order, left + idx, right, right_box, out);
  }
  Node& node = out[self];
  node.divfeat = static_cast<std::uint32_t>(cut);
  node.child2 = static_cast<std::uint32_t>(child2);
  node.divlow = left_box[cut][1];
  node.divhigh = right_box[cut][0];
  for (int a = 0; a < 3; ++a) {
    box[a][0] = std::min(left_box[a][0], right_box[a][0]);
    box[a][1] = std::max(left_box[a][1], right_box[a][1]);
  }
}

namespace {

/// nanoflann's KNNResultSet with capacity k: worst is DBL_MAX until k points are kept; a point
/// goes after every kept point at an equal distance, and one tying the worst of a full set is
/// rejected.
class KnnSet {
 public:
  KnnSet(std::size_t k, std::vector<Neighbour>& out) : k_(k), out_(out) { out_.clear(); }
  double worst() const {
    return out_.size() < k_ ? std::numeric_limits<double>::max() : out_.back().distance2;
  }
  void add(double d2, std::uint32_t index) {
    if (out_.size() == k_ && !(d2 < out_.back().distance2)) return;
    if (out_.size() < k_) out_.push_back(Neighbour{d2, index});
    std::size_t i = out_.size() - 1;
    while (i > 0 && out_[i - 1].distance2 > d2) {
      out_[i] = out_[i - 1];
      --i;
    }
    out_[i] = Neighbour{d2, index};
  }

 private:
  std::size_t k_;
  std::vector<Neighbour>& out_;
};

/// nanoflann's RadiusResultSet: every offered point strictly within the radius, in order.
class RadiusSet {
 public:
  RadiusSet(double radius2, std::vector<Neighbour>& out) : radius2_(radius2), out_(out) {
    out_.clear();
  }
  double worst() const { return radius2_; }
  void add(double d2, std::uint32_t index) {
    if (d2 < radius2_) out_.push_back(Neighbour{d2, index});
  }

 private:
  double radius2_;
  std::vector<Neighbour>& out_;
};

}  // namespace

// nanoflann 1.1.7 searchLevel, arithmetic included (the bound decides which subtrees are read,
// which never changes a result but is kept identical to be safe with rounding).
template <typename Set>
void KdTree::search_level(Set& set, const Vec3& query, std::uint32_t node_index, double mindist,
                          std::array<double, 3>& dists) const {
  const Node& node = nodes_[node_index];
  if (node.divfeat == kLeaf) {
    const double worst = set.worst();
    for (std::uint32_t i = node.first; i < node.last; ++i) {
      const double d2 = squared_distance(query, points_[i]);
      if (d2 < worst) set.add(d2, i);
    }
    return;
  }
  const std::uint32_t f = node.divfeat;
  const double v = query[f];
  const double diff1 = v - node.divlow;
  const double diff2 = v - node.divhigh;
  const bool first_child_first = diff1 + diff2 < 0;
  const std::uint32_t best = first_child_first ? node_index + 1 : node.child2;
  const std::uint32_t other = first_child_first ? node.child2 : node_index + 1;
  const double cut = first_child_first ? diff2 * diff2 : diff1 * diff1;
  search_level(set, query, best, mindist, dists);
  const double saved = dists[f];
  mindist = mindist + cut - saved;
  dists[f] = cut;
  if (mindist <= set.worst()) search_level(set, query, other, mindist, dists);
  dists[f] = saved;
}

template <typename Set>
void KdTree::search(Set& set, const Vec3& query) const {
  if (nodes_.empty()) return;
  std::array<double, 3> dists{0, 0, 0};
  double mindist = 0;
  for (int a = 0; a < 3; ++a) {
    if (query[a] < root_box_[a][0]) {
      dists[a] = (query[a] - root_box_[a][0]) * (query[a] - root_box_[a][0]);
      mindist += dists[a];
    }
    if (query[a] > root_box_[a][1]) {
      dists[a] = (query[a] - root_box_[a][1]) * (query[a] - root_box_[a][1]);
      mindist += dists[a];
    }
  }
  search_level(set, query, 0, mindist, dists);
}

void KdTree::radius_search(const Vec3& query, double radius2, std::vector<Neighbour>& out) const {
  RadiusSet set(radius2, out);
  search(set, query);
}

void KdTree::sorted_radius_search(const Vec3& query, double radius2,
                                  std::vector<Neighbour>& out) const {
  radius_search(query, radius2, out);
  // IndexDist_Sorter: the distance alone; libstdc++'s std::sort then orders ties exactly as in
  // the reference (same algorithm, same comparisons, same input order).
  std::sort(out.begin(), out.end(),
            [](const Neighbour& a, const Neighbour& b) { return a.distance2 < b.distance2; });
}

void KdTree::knn_search(const Vec3& query, std::size_t k, std::vector<Neighbour>& out) const {
  KnnSet set(std::min(k, size()), out);
  if (k == 0) return;
  search(set, query);
}

namespace {

// Smallest and largest squared distance from a point of box b to the box [lo, hi].
std::array<double, 2> box_box_distance2(const Vec3& lo, const Vec3& hi,
                                        const std::array<Vec3, 2>& b) {
  double near2 = 0;
  double far2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double gap = std::max(std::max(lo[a] - b[1][a], b[0][a] - hi[a]), 0.0);
    const double reach = std::max(std::max(lo[a] - b[0][a], b[1][a] - hi[a]), 0.0);
    near2 += gap * gap;
    far2 += reach * reach;
  }
  return {near2, far2};
}

// Squared distance from a point to the box [lo, hi].
double box_distance2(const Vec3& lo, const Vec3& hi, const Vec3& p) {
  double d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double d = std::max(std::max(lo[a] - p[a], p[a] - hi[a]), 0.0);
    d2 += d * d;
  }
  return d2;
}

// Lower bound of the squared distance from the query box to a cell, updated one axis at a time.
struct CellBound {
  Vec3 offset{0, 0, 0};
  double distance2 = 0;
};

}  // namespace

void KdTree::box_search(const Vec3& lo, const Vec3& hi, double radius2,
                        std::vector<std::uint32_t>& out) const {
  out.clear();
  if (nodes_.empty()) return;
  struct Frame {
    std::uint32_t node;
    CellBound bound;
  };
  std::vector<Frame> stack;
  stack.reserve(64);
  stack.push_back(Frame{0, CellBound{}});
  const double limit = radius2 * kPruneSlack;
  while (!stack.empty()) {
    Frame f = stack.back();
    stack.pop_back();
    for (;;) {
      const Node& node = nodes_[f.node];
      if (node.divfeat == kLeaf) {
        // Whole leaves when their box is entirely in or out of reach, else point by point
        // (branch-free append).
        const auto [near2, far2] = box_box_distance2(lo, hi, leaf_boxes_[node.child2]);
        if (near2 > limit) break;
        std::size_t m = out.size();
        out.resize(m + (node.last - node.first));
        const bool all = far2 <= radius2;
        for (std::uint32_t i = node.first; i < node.last; ++i) {
          out[m] = i;
          m += all || box_distance2(lo, hi, points_[i]) <= limit;
        }
        out.resize(m);
        break;
      }
      // First child: coordinates <= divlow; second child: >= divhigh. Gap from the box to each.
      const std::uint32_t a = node.divfeat;
      const double left_gap = lo[a] > node.divlow ? lo[a] - node.divlow : 0.0;
      const double right_gap = hi[a] < node.divhigh ? node.divhigh - hi[a] : 0.0;
      CellBound left = f.bound;
      left.distance2 += left_gap * left_gap - left.offset[a] * left.offset[a];
      left.offset[a] = left_gap;
      CellBound right = f.bound;
      right.distance2 += right_gap * right_gap - right.offset[a] * right.offset[a];
      right.offset[a] = right_gap;
      const bool visit_left = left.distance2 <= limit;
      const bool visit_right = right.distance2 <= limit;
      if (visit_left && visit_right) {
        stack.push_back(Frame{node.child2, right});
        f = Frame{f.node + 1, left};
      } else if (visit_left) {
        f = Frame{f.node + 1, left};
      } else if (visit_right) {
        f = Frame{node.child2, right};
      } else {
        break;
      }
    }
  }
}

}  // namespace qm3d::pointcloud::detail
