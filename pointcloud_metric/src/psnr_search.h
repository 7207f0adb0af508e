// psnr's nearest-neighbour search: a grid of point columns that answers a query exactly as
// pc_error's k-d tree (MpegTree, psnr_engine.h) would wherever that answer does not depend on the
// tree, and the tree itself (built only when needed) for the other queries. Internal to psnr.cpp.
//
// Why the grid's answer is the tree's (the exactness argument). Let D(p) be the squared distance
// to p as nanoflann computes it (float differences, squared and summed in double in x, y, z
// order; column_distance2 computes it the same way) and E(p) the exact squared distance. The
// tree returns the k points of smallest D among those it visits, ordered by D (equal D: by
// traversal). It skips a branch only when its lower bound (squared distances to the cut planes,
// in double: at most E(p) (1 + 1e-13) for any p in the branch) exceeds the current k-th
// distance, which only decreases. The grid finds the k + 1 points of smallest D exactly,
// g_0 <= ... <= g_k (it skips only points whose exact distance, less 1e-6 relative, exceeds its
// current (k+1)-th: their D is larger). Suppose the tree left out p_j, one of the first k: its
// k-th distance t is then >= g_k, and when it skipped p_j (or p_j's D was not below the worst
// at its leaf) the worst was >= t >= g_k, so E(p_j) (1 + 1e-13) > g_k (or D(p_j) >= g_k). So
// when each of the first k has E(p_j) (1 + kBoundRounding) < g_k and g_0 < g_1 < ... < g_k
// strictly (settled_by_distance), the tree returns exactly p_0 ... p_{k-1}, in that order (no
// equal distances: no traversal order decides). Otherwise (equal or nearly equal distances:
// voxelised clouds, duplicates) the tree answers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "psnr_engine.h"

namespace qm3d::pointcloud::detail {

/// The points sorted into columns across x and the longer of y and z (a counting sort), each
/// column sorted along the third axis. A query scans its column, then rings of columns around
/// it, skipping columns and points that cannot be among its k + 1 nearest.
class PointColumns {
 public:
  explicit PointColumns(const std::vector<Point3f>& points);

  /// The k nearest points to `query` (k <= kMaxNeighbours) in the tree's order when they are
  /// settled by distance alone (see the exactness argument above): writes them and returns
  /// true; false when the tree must answer. `next` (may be null): the (k+1)-th distance.
  bool knn(const Point3f& query, std::size_t k, std::uint32_t* indices, double* distances2,
           double* next = nullptr) const;

  std::size_t size() const { return entries_.size(); }

 private:
  struct Entry {
    Point3f p;
    std::uint32_t index;
  };
  struct Best;
  double cell(double x, int axis) const;
  static bool settled_by_distance(const Point3f& q, const Best& best, std::size_t k);
  static double gap_to(double u, long i);
  void scan_column(const Point3f& q, std::size_t col, Best& best) const;
  void search_ring(const Point3f& q, double ua, double ub, long ring, Best& best) const;

  int axis_[3] = {0, 1, 2};  // the column axes (longest extents), then the sorted axis
  double origin_[2] = {0, 0};
  double h_ = 1;  // column width
  long ga_ = 1, gb_ = 1;
  std::vector<std::uint32_t> start_;  // column c holds entries_[start_[c], start_[c + 1])
  std::vector<Entry> entries_;
};

/// The search psnr's passes use: the grid where it settles a query, pc_error's tree otherwise.
/// The same answers as MpegTree's functions of the same names.
class PsnrSearch {
 public:
  /// Searches `points` (kept by reference). `queries` (may be null): the points that will be
  /// searched; a sample of them decides up front whether the grid helps (voxelised clouds,
  /// where most queries tie, get the tree alone). `tie_threshold`: the passes' tie test.
  PsnrSearch(const std::vector<Point3f>& points, const std::vector<Point3f>* queries,
             double tie_threshold);
  ~PsnrSearch();
  PsnrSearch(const PsnrSearch&) = delete;
  PsnrSearch& operator=(const PsnrSearch&) = delete;

  std::size_t knn(const Point3f& query, std::size_t k, std::uint32_t* indices,
                  double* distances2) const;

  /// MpegTree::tie_run_knn's answer.
  template <typename Tied>
  std::size_t tie_run_knn(const Point3f& query, std::size_t first, bool expand, Tied tied,
                          std::uint32_t* indices, double* distances2) const {
    if (!grid_ || grid_->size() <= first) {
      return tree().tie_run_knn(query, first, expand, tied, indices, distances2);
    }
    // The tree's first is the grid's (settled), and its second distance is at least the
    // grid's second, g1: `tied` (monotone: |y - x| < threshold, or x == y) not holding at g1
    // holds at no larger distance, so the tree's answer is that first alone.
    double next = 0;
    if (!grid_->knn(query, 1, indices, distances2, &next)) {
      return tree().tie_run_knn(query, first, expand, tied, indices, distances2);
    }
    if (!tied(distances2[0], next)) return 1;
    // All `first` distances different: the tree's expanding query stops at `first` (it grows
    // only while the first and the last are equal), and its answer is the first-NN list.
    if (grid_->knn(query, first, indices, distances2)) return first;
    return tree().tie_run_knn(query, first, expand, tied, indices, distances2);
  }

  /// pc_error's tree (built on first use, once, by whichever thread asks first).
  const MpegTree& tree() const;

  bool uses_grid() const { return grid_ != nullptr; }

 private:
  const std::vector<Point3f>& points_;
  std::unique_ptr<PointColumns> grid_;
  mutable std::once_flag tree_once_;
  mutable std::unique_ptr<MpegTree> tree_;
};

}  // namespace qm3d::pointcloud::detail
