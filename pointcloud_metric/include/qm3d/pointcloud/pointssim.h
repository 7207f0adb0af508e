// PointSSIM (E. Alexiou and T. Ebrahimi, "Towards a point cloud structural similarity metric",
// IEEE ICMEW 2020), with the numbers of its reference code mmspg/pointssim @ 2358dd3
// (docs/pointssim.md; the rules in ../shared/docs/SPEC-POINTSSIM.md).
//
// Each cloud is sorted by its rows and its duplicate points fused; normals and curvatures come
// from a local quadric fit; each point's K nearest neighbours give four quantities (geometry:
// distances, normals: angular similarities, curvature, colour: BT.709 luma), dispersion
// estimators of those give a feature per point, and one cloud's features against those of its
// nearest points in the other give a similarity map (1 = the same), pooled into scores.
//
// Example:
//   qm3d::pointcloud::PointssimOptions o;
//   o.estimators = {PointssimEstimator::kVar, PointssimEstimator::kQcd};
//   const qm3d::MetricResult r = compute_pointssim(ref, dist, o, "ref.ply", "dist.ply");
//   qm3d::find_value(r.values, "color_var_mean");                 // symmetric: the lower one
//   qm3d::find_value(r.ref_to_dist->values, "geom_qcd_mean");     // the reference's points
#pragma once

#include <string>
#include <vector>

#include "qm3d/common/result.h"
#include "qm3d/common/types.h"

namespace qm3d::pointcloud {

/// The four attributes, in the reference's order (their JSON names: geom, norm, curv, color).
enum class PointssimAttribute { kGeom, kNorm, kCurv, kColor };
/// The seven estimators (std, var, meanad, medianad, cov, qcd, mean).
enum class PointssimEstimator { kStd, kVar, kMeanAd, kMedianAd, kCov, kQcd, kMean };
/// The three poolings of a similarity map (mean, mse, rmse).
enum class PointssimPooling { kMean, kMse, kRmse };

/// Neighbourhoods of the normal and curvature fit.
enum class PointssimFit {
  kDefaultRadius,  ///< the reference's main.m: radius round(0.01 x the reference's largest extent)
  kKnn,            ///< the fit_size nearest points, the point itself included
  kRadius,         ///< every point within fit_size (inclusive), the point itself included
};

struct PointssimOptions : RunOptions {
  /// K: the neighbourhood of the quantities, the point itself included (the reference's
  /// NEIGHBORHOOD_SIZE); at least 3.
  int neighbours = 12;
  PointssimFit fit = PointssimFit::kDefaultRadius;
  double fit_size = 0;  ///< kKnn: a count (at least 1); kRadius: a radius > 0
  /// Empty: geometry, normals, curvature, and colour when both clouds have colours.
  std::vector<PointssimAttribute> attributes;
  std::vector<PointssimEstimator> estimators{PointssimEstimator::kVar};
  std::vector<PointssimPooling> poolings{PointssimPooling::kMean};
};

/// "geom", "norm", "curv", "color"; "std", ..., "mean"; "mean", "mse", "rmse".
const char* pointssim_name(PointssimAttribute a);
const char* pointssim_name(PointssimEstimator e);
const char* pointssim_name(PointssimPooling p);
/// The value name of one combination: "geom_var_mean".
std::string pointssim_value_name(PointssimAttribute a, PointssimEstimator e, PointssimPooling p);
/// Every value name (4 x 7 x 3), attributes outermost, then estimators, then poolings.
std::vector<std::string> pointssim_value_names();
/// A comma-separated list of names, or "all" (case-insensitive); std::invalid_argument naming
/// `option` and the known names otherwise. An empty list is refused.
std::vector<PointssimAttribute> parse_pointssim_attributes(const std::string& list,
                                                           const std::string& option);
std::vector<PointssimEstimator> parse_pointssim_estimators(const std::string& list,
                                                           const std::string& option);
std::vector<PointssimPooling> parse_pointssim_poolings(const std::string& list,
                                                       const std::string& option);

/// PointSSIM of `distorted` against `reference` (the reference's A = reference, B = distorted).
/// Directions: ref_to_dist = the reference's AB (A's points scored against B), dist_to_ref = BA;
/// symmetric (the default): both, each value the lower of the two (a NaN one ignored).
/// Values: every requested attribute x estimator x pooling, by pointssim_value_name, in the
/// result (symmetric or the one direction) and in each direction; a value that is NaN (no
/// finite similarity at all, e.g. COV of curvatures that are all 0) is left out with a warning.
/// Score: color_var_mean when colour is compared, else geom_var_mean (else the first value
/// requested). Per-element: the score's similarity map of each direction, on the iterated
/// cloud's points in input order (a fused duplicate gets its fused point's value).
/// InputError / FormatError naming the file: an empty or non-finite cloud, fewer points than a
/// fit or K needs, no colour when colour is asked; std::invalid_argument for bad options (the
/// default radius rounding to 0).
MetricResult compute_pointssim(const ColoredCloud& reference, const ColoredCloud& distorted,
                               const PointssimOptions& options,
                               const std::string& reference_name = "reference",
                               const std::string& distorted_name = "distorted");

}  // namespace qm3d::pointcloud
