// Batched neighbour queries: the points of a k-d tree near a small box, gathered once and then
// filtered exactly for each query inside the box.
//
// Queries come a leaf at a time (about a dozen nearby points): one box search replaces a dozen
// tree traversals, and each query scans a short contiguous array. Every candidate's squared
// distance is computed exactly as KdTree::squared_distance does, so the results are the tree's.
#pragma once

#include <cstdint>
#include <vector>

#include "kd_tree.h"

namespace qm3d::pointcloud::detail {

/// Axis-aligned bounding box of tree points [first, last).
struct Box {
  Vec3 lo{0, 0, 0};
  Vec3 hi{0, 0, 0};
};
Box box_of(const std::vector<Vec3>& points, std::uint32_t first, std::uint32_t last);

class CandidateSet {
 public:
  /// Gathers every point of `tree` within sqrt(radius2) of `box`.
  void gather(const KdTree& tree, const Box& box, double radius2);

  /// Candidates strictly within sqrt(radius2) of q, in tree order. Exact (the set
  /// tree.radius_search returns) when q lies in the gathered box and radius2 <= the gathered
  /// radius2.
  void radius(const Vec3& q, double radius2, std::vector<Neighbour>& out);

  /// A list held by the set: valid until its next query or gather.
  struct Selection {
    const Neighbour* data = nullptr;
    std::size_t count = 0;
    std::size_t size() const { return count; }
    const Neighbour& operator[](std::size_t i) const { return data[i]; }
  };
  /// radius() without copying the list out.
  Selection radius(const Vec3& q, double radius2);

  /// What knn found besides its list.
  struct Knn {
    double kth_distance2 = 0;  ///< the k-th nearest squared distance (0 when k = 0)
    /// Another candidate ties the k-th distance: which of them is kept depends on the search
    /// order (KdTree::knn_search decides as the reference does).
    bool tie_at_kth = false;
  };

  /// The k nearest candidates sorted by (distance, index). Only candidates within
  /// sqrt(knn_bound2) are ranked. Exact (the tree's kNN up to the order of equal distances)
  /// when q lies in the box and q's k-th nearest distance in the tree is at most both
  /// sqrt(knn_bound2) and the gathered radius.
  Knn knn(const Vec3& q, std::size_t k, double knn_bound2, std::vector<Neighbour>& nearest);

  std::size_t size() const { return size_; }

 private:
  template <bool kStrict>
  Selection select(const Vec3& q, double bound2);
  template <bool kStrict>
  void select(const Vec3& q, double bound2, std::vector<Neighbour>& out);
  void distances(const Vec3& q);
  template <bool kStrict>
  std::size_t select_scalar(double bound2, std::vector<Neighbour>& out) const;

  std::size_t size_ = 0;
  /// Candidates in tree order: indices and coordinates (structure of arrays), padded to a
  /// multiple of kLanes with index 0 at +infinity (read by the vector path, never selected).
  std::vector<std::uint32_t> index_;
  std::vector<double> x_, y_, z_;
  std::vector<double> d2_;           // squared distances to the current query (scalar path)
  std::vector<Neighbour> selected_;  // the vector path's output before it is copied out
  std::vector<Neighbour> survivors_;
};

}  // namespace qm3d::pointcloud::detail
