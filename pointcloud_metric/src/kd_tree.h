// An exact double-precision k-d tree for fixed-radius and k-nearest-neighbour queries.
//
// Why not only PCL's KdTreeFLANN: FLANN stores float coordinates and compares float distances,
// while the reference (MEPP-team/PCQM, nanoflann 1.1.7 over double coordinates) keeps a point when
// its double squared distance, summed as dx*dx + dy*dy + dz*dz, is strictly below r^2. This tree
// computes exactly that value for every candidate, so its neighbour sets are the reference's by
// construction (see pcl_search.h for the PCL variant, which must re-filter its candidates).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <vector>

#include "qm3d/common/types.h"

namespace qm3d::pointcloud::detail {

/// One search result: the point's index in tree order and its squared distance to the query.
struct Neighbour {
  double distance2 = 0;
  std::uint32_t index = 0;
};

/// Squared distance as nanoflann's L2 adaptor sums it for 3-D points (left to right).
inline double squared_distance(const Vec3& a, const Vec3& b) {
  const double dx = a[0] - b[0];
  const double dy = a[1] - b[1];
  const double dz = a[2] - b[2];
  return dx * dx + dy * dy + dz * dz;
}

/// Orders results by squared distance, ties by index (deterministic).
void sort_by_distance(std::vector<Neighbour>& neighbours);

/// A balanced k-d tree over #P points. The tree stores the points in its own order (spatially
/// coherent: consecutive indices are close in space); every index it returns is a tree index.
class KdTree {
 public:
  /// Builds the tree, in parallel over subtrees (OpenMP tasks, `threads` threads, 0 = the
  /// OpenMP default) when called outside a parallel region. The tree does not depend on the
  /// thread count. At most 2^32 - 2 points.
  explicit KdTree(const std::vector<Vec3>& points, int threads = 0);

  std::size_t size() const { return points_.size(); }
  /// Positions in tree order.
  const std::vector<Vec3>& points() const { return points_; }
  /// Tree index -> index in the input vector.
  const std::vector<std::uint32_t>& input_index() const { return input_index_; }

  /// All points with squared distance strictly below `radius2`, in tree order (unsorted by
  /// distance). `out` is overwritten.
  void radius_search(const Vec3& query, double radius2, std::vector<Neighbour>& out) const;

  /// The min(k, size) nearest points sorted by distance. Among equal distances the point found
  /// first is kept, as in nanoflann's KNNResultSet. `out` is overwritten.
  void knn_search(const Vec3& query, std::size_t k, std::vector<Neighbour>& out) const;

  /// Both searches in one traversal: the k nearest (sorted) and everything strictly within
  /// sqrt(radius2) (unsorted). Same results as the two calls above.
  void knn_radius_search(const Vec3& query, std::size_t k, double radius2,
                         std::vector<Neighbour>& nearest, std::vector<Neighbour>& within) const;

  /// Every point whose distance to the box [lo, hi] is at most sqrt(radius2) (plus a relative
  /// 1e-9 of slack), in tree order: a superset of what radius_search(q, radius2) returns for any
  /// q inside the box. `out` is overwritten.
  void box_search(const Vec3& lo, const Vec3& hi, double radius2,
                  std::vector<std::uint32_t>& out) const;

  /// The leaves as tree-index ranges [first, last), in tree order (they partition 0..size).
  const std::vector<std::array<std::uint32_t, 2>>& leaves() const { return leaves_; }

 private:
  struct Node {
    double split = 0;         // inner: split coordinate
    std::uint32_t axis = 0;   // inner: 0..2, leaf: kLeaf
    std::uint32_t first = 0;  // inner: right child; leaf: first point
    std::uint32_t last = 0;   // leaf: one past the last point
    std::uint32_t leaf = 0;   // leaf: its position in leaves_ / leaf_boxes_
  };
  struct Item;
  static constexpr std::uint32_t kLeaf = 3;

  void index_leaves();
  void build(std::vector<Item>& items, std::size_t begin, std::size_t end, std::size_t node,
             const std::map<std::size_t, std::size_t>& subtree_nodes);
  /// Depth-first descent from `node`, nearer child first; far children are kept with their cell
  /// bound and skipped when it exceeds limit() (re-checked when popped, as limit() may shrink).
  /// on_leaf(first, last) receives the point range of every leaf reached.
  template <typename Limit, typename Leaf>
  void descend(std::uint32_t node, const Vec3& query, const Limit& limit, Leaf&& on_leaf) const;
  template <typename Visitor>
  void radius_visit(std::uint32_t node, const Vec3& query, double radius2, Visitor& visit) const;
  template <typename Set>
  void knn_visit(std::uint32_t node, const Vec3& query, Set& set) const;

  std::vector<Vec3> points_;
  std::vector<std::uint32_t> input_index_;
  std::vector<Node> nodes_;
  std::vector<std::array<std::uint32_t, 2>> leaves_;
  std::vector<std::array<Vec3, 2>> leaf_boxes_;  // tight bounding box of each leaf's points
};

}  // namespace qm3d::pointcloud::detail
