// The k-d tree of the reference implementation: the tree nanoflann 1.1.7 builds
// (KDTreeSingleIndexAdaptor, leaf size 10, as MEPP-team/PCQM configures it) and its exact search
// order, over double coordinates. Written from the description in docs NANOFLANN-1.1.7.md.
//
// Why the same tree and not just any exact one: among points at the same distance from a query
// (everywhere on voxelised clouds), the reference keeps the one its traversal reaches first —
// as the nearest-neighbour colour, as the k-th neighbour of a kNN set, and in the order of the
// rows of its quadric fits. Only nanoflann 1.1.7's tree, searched in its order, reproduces those
// choices (1.2.3 changed the split rule: Debian's nanoflann 1.4.3 builds another tree).
//
// The rules, in the order the build and the searches apply them (NANOFLANN-1.1.7.md §1, §3, §4):
// - Build over the points in input order. A range of at most 10 points is a leaf. Otherwise the
//   cut dimension is chosen by middleSplit_ from the node's *inherited* box (the root's tight box
//   clipped by the ancestors' cut values): dims whose span exceeds (1 - 1e-5) of the largest
//   qualify; for each qualifying dim in ascending order, the spread of the points along the
//   *currently chosen* dim (a bug of 1.1.7, fixed in 1.2.3) is compared strictly with the best so
//   far. The cut value is the middle of the inherited box clamped to the points' range; a two-pass
//   Hoare partition (< cut, then <= cut) gives lim1 <= lim2, and the split index is lim1 if it is
//   above count/2, else lim2 if below, else count/2. A node keeps divlow = the largest coordinate
//   of its first child and divhigh = the smallest of its second child along the cut dim.
// - Search: from the root's tight box distances, at each node the first child is visited first
//   iff (v - divlow) + (v - divhigh) < 0 (v = the query's coordinate; the exact midpoint goes to
//   the second child), then the other iff the incrementally updated bound
//   (bound + cut^2) - old_axis_term is <= the result set's current worst. A leaf reads the worst
//   once and offers, in tree order, each point whose distance is strictly below it.
// - kNN result set: a point is inserted after every kept point at an equal distance and is
//   rejected when the set is full and it only ties the worst: the first k points of the traversal
//   ordered by distance. Radius result set: every point with d^2 < r^2, in traversal order; the
//   reference sorts it with std::sort on the distance alone (libstdc++ introsort: not stable above
//   16 elements), which sorted_radius_search reproduces by calling the same routine on the same
//   input order.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "qm3d/common/types.h"

namespace qm3d::pointcloud::detail {

/// One search result: the point's index in tree order and its squared distance to the query.
struct Neighbour {
  double distance2 = 0;
  std::uint32_t index = 0;
};

/// Squared distance as the reference sums it for 3-D points: (dx dx + dy dy) + dz dz.
inline double squared_distance(const Vec3& a, const Vec3& b) {
  const double dx = a[0] - b[0];
  const double dy = a[1] - b[1];
  const double dz = a[2] - b[2];
  return dx * dx + dy * dy + dz * dz;
}

/// (squared distance, index) ascending: a total order on a list of distinct points without NaN
/// distances.
struct NeighbourOrder {
  bool operator()(const Neighbour& a, const Neighbour& b) const {
    return a.distance2 < b.distance2 || (a.distance2 == b.distance2 && a.index < b.index);
  }
};

/// Orders results by squared distance, ties by index (deterministic; the reference's order
/// whenever no two distances are equal).
void sort_by_distance(std::vector<Neighbour>& neighbours);

/// True when two consecutive entries of a distance-sorted list have equal distances.
bool has_ties(const std::vector<Neighbour>& sorted);

/// nanoflann 1.1.7's k-d tree over #P points. The tree stores the points in its own order (the
/// permuted index array of nanoflann, spatially coherent); every index it returns is a tree
/// index.
class KdTree {
 public:
  /// Points per leaf (MEPP-team/PCQM: KDTreeSingleIndexAdaptorParams(10)).
  static constexpr std::size_t kLeafSize = 10;

  /// Builds the tree, in parallel over large subtrees (OpenMP tasks, `threads` threads, 0 = the
  /// OpenMP default) when called outside a parallel region. The tree does not depend on the
  /// thread count. At most 2^32 - 2 points.
  explicit KdTree(const std::vector<Vec3>& points, int threads = 0);

  std::size_t size() const { return points_.size(); }
  /// Positions in tree order.
  const std::vector<Vec3>& points() const { return points_; }
  /// Tree index -> index in the input vector.
  const std::vector<std::uint32_t>& input_index() const { return input_index_; }

  /// All points with squared distance strictly below `radius2`, in the reference's traversal
  /// order (its `radiusSearch` with sorted = false). `out` is overwritten.
  void radius_search(const Vec3& query, double radius2, std::vector<Neighbour>& out) const;

  /// radius_search, then std::sort on the distance alone: the reference's `radiusSearch` with
  /// sorted = true, ties included.
  void sorted_radius_search(const Vec3& query, double radius2, std::vector<Neighbour>& out) const;

  /// The min(k, size) nearest points sorted by distance; among equal distances the one the
  /// traversal reaches first comes first and wins the last place (the reference's `knnSearch`).
  /// `out` is overwritten.
  void knn_search(const Vec3& query, std::size_t k, std::vector<Neighbour>& out) const;

  /// Every point whose distance to the box [lo, hi] is at most sqrt(radius2) (plus a relative
  /// 1e-9 of slack), in tree order: a superset of what radius_search(q, radius2) returns for any
  /// q inside the box. `out` is overwritten.
  void box_search(const Vec3& lo, const Vec3& hi, double radius2,
                  std::vector<std::uint32_t>& out) const;

  /// The leaves as tree-index ranges [first, last), in tree order (they partition 0..size).
  const std::vector<std::array<std::uint32_t, 2>>& leaves() const { return leaves_; }

 private:
  struct Node {
    double divlow = 0;          // inner: largest coordinate of the first child along divfeat
    double divhigh = 0;         // inner: smallest coordinate of the second child along divfeat
    std::uint32_t divfeat = 0;  // inner: 0..2, leaf: kLeaf
    std::uint32_t child2 =
        0;  // inner: the second child (the first is the next node); leaf: its index in leaves_
    std::uint32_t first = 0;  // leaf: first point
    std::uint32_t last = 0;   // leaf: one past the last point
  };
  using Bounds = std::array<std::array<double, 2>, 3>;  // per axis {low, high}
  static constexpr std::uint32_t kLeaf = 3;

  void build(std::vector<std::uint32_t>& order, std::size_t left, std::size_t right, Bounds& box,
             std::vector<Node>& out);
  void index_leaves();
  template <typename Set>
  void search_level(Set& set, const Vec3& query, std::uint32_t node, double mindist,
                    std::array<double, 3>& dists) const;
  template <typename Set>
  void search(Set& set, const Vec3& query) const;

  std::vector<Vec3> points_;
  std::vector<std::uint32_t> input_index_;
  std::vector<Node> nodes_;
  Bounds root_box_{};
  std::vector<std::array<std::uint32_t, 2>> leaves_;
  std::vector<std::array<Vec3, 2>> leaf_boxes_;  // tight bounding box of each leaf's points
};

}  // namespace qm3d::pointcloud::detail
