// PointSSIM's stages (pointssim.cpp): the prepared clouds, the neighbour search in the
// reference's order, and the quadric fit of normals and curvatures (pointssim_fit.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "kd_tree.h"
#include "qm3d/common/types.h"
#include "qm3d/pointcloud/pointssim.h"

namespace qm3d::pointcloud::detail {

/// A cloud as the reference scores it: rows sorted (x, then y, then z) and duplicate points
/// fused (pc_fuse_points).
struct SsimCloud {
  std::vector<Vec3> points;
  /// 8-bit colours, one per point; empty when the cloud has none.
  std::vector<std::array<std::uint8_t, 3>> colours;
  std::vector<std::uint32_t> of_input;  ///< input point -> its (fused) point
  std::size_t duplicates = 0;           ///< input points fused into an earlier one
};

/// Sorts and fuses `cloud` (its colours when `with_colours`): a fused point's colour is the
/// mean of its duplicates' 8-bit values, rounded half away from zero (the reference's
/// round(mean)). NumericError naming `name` when a coordinate is not finite.
SsimCloud prepare_cloud(const ColoredCloud& cloud, bool with_colours, const std::string& name);

/// Exact neighbour searches over a sorted, fused cloud in the order of the reference's
/// knnsearch / rangesearch: increasing squared distance ((dx^2 + dy^2) + dz^2), exact ties to
/// the lower row. The module's k-d tree finds the candidates (its own tie order is
/// nanoflann's), re-sorted here; indices are rows of the cloud.
class OrderedSearch {
 public:
  OrderedSearch(const std::vector<Vec3>& points, int threads);

  std::size_t size() const { return tree_.size(); }
  /// The min(k, size) nearest rows, in the reference's order, with their squared distances.
  void knn(const Vec3& query, std::size_t k, std::vector<Neighbour>& out) const;
  /// Every row within `radius` (sqrt(d^2) <= radius), in the same order.
  void within(const Vec3& query, double radius, std::vector<Neighbour>& out) const;

 private:
  /// Tree indices -> rows, distances as the reference sums them, then the reference's order.
  void to_rows(std::vector<Neighbour>& found) const;

  KdTree tree_;
};

/// The fit's neighbourhood: the `count` nearest points, or every point within `radius`.
struct FitNeighbourhood {
  std::size_t count = 0;  ///< > 0: k nearest
  double radius = 0;      ///< used when count == 0
};

/// Normals and curvatures of every row (pc_estimate_norm_curv_qfit's rules; NaN where the
/// reference leaves NaN: a neighbourhood of one point, a fit without a solution).
struct SurfaceEstimates {
  std::vector<Vec3> normals;
  std::vector<double> curvatures;
  /// A knn fit's search also gives the `k` nearest rows of every row (row i's at i * k): the
  /// features' neighbourhoods, kept so that they are not searched again. Empty otherwise.
  std::vector<std::uint32_t> nearest;
  std::size_t k = 0;
};

/// The normals and curvatures of every row; a knn fit also keeps each row's `k` nearest rows.
SurfaceEstimates estimate_surface(const std::vector<Vec3>& points, const OrderedSearch& search,
                                  const FitNeighbourhood& fit, std::size_t k, int threads);

/// Each requested estimator of each requested attribute, per row of a cloud:
/// maps[a * estimators.size() + e] is estimator e of attribute a (in the order of the lists).
struct FeatureMaps {
  std::vector<std::vector<double>> maps;
};

/// The feature maps of a cloud over its K nearest rows (self first; pointssim's quantities:
/// geometry the K - 1 distances, normals the K - 1 angular similarities, curvature and colour
/// luma the K values). `surface` is needed for normals and curvature; its kept neighbourhoods are
/// used when they are the K nearest.
FeatureMaps feature_maps(const SsimCloud& cloud, const OrderedSearch& search,
                         const SurfaceEstimates* surface, std::size_t k,
                         const std::vector<PointssimAttribute>& attributes,
                         const std::vector<PointssimEstimator>& estimators, int threads);

/// One estimator of the values q[0..m) (STD, VAR with N - 1; MeanAD; MedianAD; COV = std /
/// mean; QCD with MATLAB's quantile; Mean), NaN as the reference's Octave functions give it.
/// `scratch` holds a sorted copy.
double estimate(PointssimEstimator e, const double* q, std::size_t m, std::vector<double>& scratch);

}  // namespace qm3d::pointcloud::detail
