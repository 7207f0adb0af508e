#include "kd_tree.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

namespace qm3d::pointcloud::detail {
namespace {

/// Points per leaf: of 8, 12, 16, 24 and 32, 16 and 32 were fastest (within noise) on the 1M and
/// 2M benchmark spheres (bench_pcqm, one thread); nanoflann's default is 10.
constexpr std::size_t kLeafSize = 16;
/// Lists up to this size are insertion-sorted (about 20% faster than std::sort at 32 elements).
constexpr std::size_t kInsertionSortMax = 64;
/// Subtrees larger than this are built as separate OpenMP tasks.
constexpr std::size_t kTaskThreshold = 1 << 15;
/// Cells are pruned only when their lower-bound distance exceeds the bound by this factor, so
/// that rounding in the incremental bound can never drop a point the exact leaf test would keep.
constexpr double kPruneSlack = 1.0 + 1e-9;

// Number of nodes of a subtree of n points (median halving until kLeafSize), memoised: at each
// depth there are at most two distinct subtree sizes.
std::size_t node_count(std::size_t n, std::map<std::size_t, std::size_t>& memo) {
  if (n <= kLeafSize) return 1;
  auto it = memo.find(n);
  if (it != memo.end()) return it->second;
  const std::size_t count = 1 + node_count(n / 2, memo) + node_count(n - n / 2, memo);
  memo.emplace(n, count);
  return count;
}

}  // namespace

struct KdTree::Item {
  Vec3 position;
  std::uint32_t input_index;
};

void sort_by_distance(std::vector<Neighbour>& neighbours) {
  const auto closer = [](const Neighbour& a, const Neighbour& b) {
    return a.distance2 < b.distance2 || (a.distance2 == b.distance2 && a.index < b.index);
  };
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

KdTree::KdTree(const std::vector<Vec3>& points, int threads) {
  if (points.size() >= std::numeric_limits<std::uint32_t>::max()) {
    throw std::length_error("k-d tree: too many points (" + std::to_string(points.size()) + ")");
  }
  std::vector<Item> items(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    items[i] = Item{points[i], static_cast<std::uint32_t>(i)};
  }
  std::map<std::size_t, std::size_t> subtree_nodes;
  nodes_.resize(points.empty() ? 0 : node_count(points.size(), subtree_nodes));
  if (!points.empty()) {
#pragma omp parallel num_threads( \
    threads > 0 ? threads         \
                : omp_get_max_threads()) if (!omp_in_parallel() && items.size() > kTaskThreshold)
#pragma omp single
    build(items, 0, items.size(), 0, subtree_nodes);
  }
  points_.resize(items.size());
  input_index_.resize(items.size());
  for (std::size_t i = 0; i < items.size(); ++i) {
    points_[i] = items[i].position;
    input_index_[i] = items[i].input_index;
  }
  index_leaves();
}

void KdTree::index_leaves() {
  for (Node& node : nodes_) {  // pre-order: leaves come in tree order
    if (node.axis != kLeaf) continue;
    node.leaf = static_cast<std::uint32_t>(leaves_.size());
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

// Builds the subtree of items [begin, end) at nodes_[node] (pre-order: left child = node + 1).
void KdTree::build(std::vector<Item>& items, std::size_t begin, std::size_t end, std::size_t node,
                   const std::map<std::size_t, std::size_t>& subtree_nodes) {
  const std::size_t n = end - begin;
  if (n <= kLeafSize) {
    nodes_[node] = Node{0, kLeaf, std::uint32_t(begin), std::uint32_t(end)};
    return;
  }
  Vec3 lo = items[begin].position;
  Vec3 hi = lo;
  for (std::size_t i = begin + 1; i < end; ++i) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], items[i].position[a]);
      hi[a] = std::max(hi[a], items[i].position[a]);
    }
  }
  std::uint32_t axis = 0;
  for (std::uint32_t a = 1; a < 3; ++a) {
    if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
  }
  const std::size_t mid = begin + n / 2;
  std::nth_element(
      items.begin() + begin, items.begin() + mid, items.begin() + end,
      [axis](const Item& a, const Item& b) { return a.position[axis] < b.position[axis]; });
  const std::size_t left_nodes = n / 2 <= kLeafSize ? 1 : subtree_nodes.at(n / 2);
  const std::size_t right = node + 1 + left_nodes;
  nodes_[node] = Node{items[mid].position[axis], axis, std::uint32_t(right), 0};
#pragma omp task default(shared) if (n > kTaskThreshold)
  build(items, begin, mid, node + 1, subtree_nodes);
  build(items, mid, end, right, subtree_nodes);
#pragma omp taskwait
}

namespace {

// Lower bound of the squared distance from the query to a cell, updated one axis at a time
// (Arya & Mount's incremental distance, as nanoflann does).
struct CellBound {
  Vec3 offset{0, 0, 0};
  double distance2 = 0;
};

}  // namespace

template <typename Limit, typename Leaf>
void KdTree::descend(std::uint32_t node_index, const Vec3& query, const Limit& limit,
                     Leaf&& on_leaf) const {
  struct Frame {
    std::uint32_t node;
    CellBound bound;
  };
  Frame stack[64];
  int top = 0;
  stack[top++] = Frame{node_index, CellBound{}};
  while (top > 0) {
    Frame f = stack[--top];
    if (f.bound.distance2 > limit()) continue;
    for (;;) {
      const Node& node = nodes_[f.node];
      if (node.axis == kLeaf) {
        on_leaf(node.first, node.last);
        break;
      }
      const double diff = query[node.axis] - node.split;
      const std::uint32_t near_child = diff < 0 ? f.node + 1 : node.first;
      const std::uint32_t far_child = diff < 0 ? node.first : f.node + 1;
      CellBound far = f.bound;
      far.distance2 += diff * diff - far.offset[node.axis] * far.offset[node.axis];
      far.offset[node.axis] = diff;
      if (far.distance2 <= limit()) stack[top++] = Frame{far_child, far};
      f.node = near_child;
    }
  }
}

template <typename Visitor>
void KdTree::radius_visit(std::uint32_t node_index, const Vec3& query, double radius2,
                          Visitor& visit) const {
  const double limit = radius2 * kPruneSlack;
  descend(node_index, query, [limit] { return limit; },
          [&](std::uint32_t first, std::uint32_t last) {
            for (std::uint32_t i = first; i < last; ++i) {
              const double d2 = squared_distance(query, points_[i]);
              if (d2 < radius2) visit(d2, i);
            }
          });
}

void KdTree::radius_search(const Vec3& query, double radius2, std::vector<Neighbour>& out) const {
  out.clear();
  if (nodes_.empty()) return;
  auto visit = [&out](double d2, std::uint32_t i) { out.push_back(Neighbour{d2, i}); };
  radius_visit(0, query, radius2, visit);
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

}  // namespace

void KdTree::box_search(const Vec3& lo, const Vec3& hi, double radius2,
                        std::vector<std::uint32_t>& out) const {
  out.clear();
  if (nodes_.empty()) return;
  struct Frame {
    std::uint32_t node;
    CellBound bound;
  };
  Frame stack[64];
  int top = 0;
  stack[top++] = Frame{0, CellBound{}};
  const double limit = radius2 * kPruneSlack;
  while (top > 0) {
    Frame f = stack[--top];
    for (;;) {
      const Node& node = nodes_[f.node];
      if (node.axis == kLeaf) {
        // Whole leaves when their box is entirely in or out of reach, else point by point
        // (branch-free append).
        const auto [near2, far2] = box_box_distance2(lo, hi, leaf_boxes_[node.leaf]);
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
      // Left child: coordinates <= split; right child: >= split. Gap from the box to each.
      const std::uint32_t a = node.axis;
      const double left_gap = lo[a] > node.split ? lo[a] - node.split : 0.0;
      const double right_gap = hi[a] < node.split ? node.split - hi[a] : 0.0;
      CellBound left = f.bound;
      left.distance2 += left_gap * left_gap - left.offset[a] * left.offset[a];
      left.offset[a] = left_gap;
      CellBound right = f.bound;
      right.distance2 += right_gap * right_gap - right.offset[a] * right.offset[a];
      right.offset[a] = right_gap;
      const bool visit_left = left.distance2 <= limit;
      const bool visit_right = right.distance2 <= limit;
      if (visit_left && visit_right) {
        stack[top++] = Frame{node.first, right};
        f = Frame{f.node + 1, left};
      } else if (visit_left) {
        f = Frame{f.node + 1, left};
      } else if (visit_right) {
        f = Frame{node.first, right};
      } else {
        break;
      }
    }
  }
}

namespace {

// The k best so far, sorted; insertion keeps the earlier of equal distances first and rejects a
// candidate equal to the current worst once full (nanoflann KNNResultSet::addPoint).
class KnnSet {
 public:
  KnnSet(std::size_t k, std::vector<Neighbour>& out) : k_(k), out_(out) { out_.clear(); }
  double worst() const {
    if (k_ == 0) return -std::numeric_limits<double>::infinity();
    return out_.size() < k_ ? std::numeric_limits<double>::infinity() : out_.back().distance2;
  }
  void add(double d2, std::uint32_t index) {
    if (k_ == 0 || (out_.size() == k_ && !(d2 < out_.back().distance2))) return;
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

// kNN plus every point strictly within a radius; prunes with the larger of the two bounds.
class KnnRadiusSet {
 public:
  KnnRadiusSet(std::size_t k, double radius2, std::vector<Neighbour>& nearest,
               std::vector<Neighbour>& within)
      : knn_(k, nearest), radius2_(radius2), within_(within) {
    within_.clear();
  }
  double worst() const { return std::max(knn_.worst(), radius2_); }
  void add(double d2, std::uint32_t index) {
    if (d2 < radius2_) within_.push_back(Neighbour{d2, index});
    knn_.add(d2, index);
  }

 private:
  KnnSet knn_;
  double radius2_;
  std::vector<Neighbour>& within_;
};

}  // namespace

template <typename Set>
void KdTree::knn_visit(std::uint32_t node_index, const Vec3& query, Set& set) const {
  descend(node_index, query, [&set] { return set.worst() * kPruneSlack; },
          [&](std::uint32_t first, std::uint32_t last) {
            for (std::uint32_t i = first; i < last; ++i) set.add(squared_distance(query, points_[i]), i);
          });
}

void KdTree::knn_search(const Vec3& query, std::size_t k, std::vector<Neighbour>& out) const {
  KnnSet set(std::min(k, size()), out);
  if (nodes_.empty() || k == 0) return;
  knn_visit(0, query, set);
}

void KdTree::knn_radius_search(const Vec3& query, std::size_t k, double radius2,
                               std::vector<Neighbour>& nearest,
                               std::vector<Neighbour>& within) const {
  KnnRadiusSet set(std::min(k, size()), radius2, nearest, within);
  if (nodes_.empty()) return;
  knn_visit(0, query, set);
}

}  // namespace qm3d::pointcloud::detail
