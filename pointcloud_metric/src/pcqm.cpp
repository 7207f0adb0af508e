#include "qm3d/pointcloud/pcqm.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "pcqm_internal.h"
#include "qm3d/common/color.h"
#include "qm3d/common/error.h"
#include "qm3d/common/pooling.h"

namespace qm3d::pointcloud {
namespace {

/// Relative gap between the reference's |min| + |max| box size and the true longest side above
/// which compute_pcqm warns (the radii then differ by as much from the translation-free ones).
constexpr double kBboxQuirkWarningGap = 0.01;

/// `v` with `digits` significant digits (all of them by default).
std::string number(double v, int digits = 17) {
  std::ostringstream o;
  o.precision(digits);
  o << v;
  return o.str();
}

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("PCQM options: " + message);
}

void validate(const PcqmOptions& o) {
  require(std::isfinite(o.radius_rel) && o.radius_rel > 0,
          "radius_rel must be positive and finite, got " + number(o.radius_rel));
  require(o.knn >= 1, "knn must be at least 1, got " + std::to_string(o.knn));
  require(std::isfinite(o.radius_factor) && o.radius_factor > 0,
          "radius_factor must be positive and finite, got " + number(o.radius_factor));
  require(o.threads >= 0,
          "threads must be 0 (OpenMP default) or positive, got " + std::to_string(o.threads));
  require(o.bbox == BboxMode::kReference || o.bbox == BboxMode::kExtent, "unknown bbox mode");
}

void validate(const ColoredCloud& cloud, const std::string& name) {
  if (cloud.positions.empty()) throw NumericError("PCQM: the " + name + " cloud is empty");
  if (cloud.colors.size() != cloud.positions.size()) {
    throw NumericError("PCQM: the " + name + " cloud has " +
                       std::to_string(cloud.positions.size()) + " points but " +
                       std::to_string(cloud.colors.size()) + " colours");
  }
  for (std::size_t i = 0; i < cloud.positions.size(); ++i) {
    const Vec3& p = cloud.positions[i];
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      throw NumericError("PCQM: point " + std::to_string(i) + " of the " + name +
                         " cloud has a non-finite coordinate");
    }
  }
}

/// maxDim of the iterated cloud per `mode`; warns when the reference's quirk is far off.
double max_dim(const ColoredCloud& cloud, BboxMode mode, const std::string& name,
               std::vector<std::string>& warnings) {
  const double extent = bounding_box(cloud.positions).longest_side();
  if (!(extent > 0)) {
    throw NumericError("PCQM: the " + name + " cloud's bounding box has zero size");
  }
  if (mode == BboxMode::kExtent) return extent;
  const double quirk = detail::reference_max_dim(cloud.positions);
  if (std::abs(quirk - extent) > kBboxQuirkWarningGap * extent) {
    warnings.push_back("PCQM: the " + name + " cloud's box size |min| + |max| = " + number(quirk) +
                       " differs from its longest side " + number(extent) +
                       " (the cloud does not straddle the origin); radii and curvatures follow "
                       "the reference implementation's value; the extent bbox mode (qm3d --bbox extent) gives a "
                       "translation-invariant score");
  }
  return quirk;
}

/// Rounded up to two significant digits.
double round_up_2(double v) {
  const double unit = std::pow(10.0, std::floor(std::log10(v)) - 1);
  return std::ceil(v / unit) * unit;
}

/// SPEC-PCQM §9.5: a quadric fit with fewer than six independent points has no unique solution
/// (and a nearly singular one barely has one); the reference returns its QR's basic solution,
/// whose rounding differs between Eigen versions (its bundled 3.3.5 and Debian's 3.4), and
/// qm3d's value is the one with Debian's Eigen. One warning per kind of fit that is
/// underdetermined on more than 1% of the points, with the setting that avoids it.
void warn_of_underdetermined_fits(const detail::DirectionOutput& out, std::size_t points,
                                  const std::string& name, const PcqmOptions& o,
                                  std::vector<std::string>& warnings) {
  const auto share = [points](std::size_t count) {
    return number(100.0 * double(count) / double(points), 3) + "% of the ";
  };
  const std::string consequence =
      ": they are not determined by the points (fewer than six independent ones, or nearly so), "
      "so their values depend on the rounding of the linear-algebra library (the reference's "
      "bundled Eigen 3.3.5 and Eigen 3.4 differ there; qm3d gives the Eigen 3.4 value)";
  const double limit = detail::kUnderdeterminedShare * double(points);
  if (double(out.underdetermined_curvature) > limit) {
    std::string w = "PCQM: " + share(out.underdetermined_curvature) + name +
                    " cloud's points have an underdetermined curvature fit (quadric on the "
                    "points within the curvature radius " + number(o.radius_rel, 3) +
                    " x box size)" + consequence + " and so do F1-F3";
    w += out.suggestion.radius_rel > 0
             ? "; with a curvature radius of " + number(round_up_2(out.suggestion.radius_rel), 2) +
                   " (qm3d --radius, reference -r) fewer than 0.5% of a sample of points are"
             : "; no curvature radius up to 16 times this one avoids it";
    warnings.push_back(w);
  }
  if (double(out.underdetermined_match) > limit) {
    std::string w = "PCQM: " + share(out.underdetermined_match) + name +
                    " cloud's points have an underdetermined correspondence fit (quadric on "
                    "the " + std::to_string(o.knn) + " nearest points of the other cloud)" +
                    consequence + " and so do the Gaussian weights of every feature";
    w += out.suggestion.knn > 0
             ? "; with knn " + std::to_string(out.suggestion.knn) +
                   " (qm3d --knn, reference -knn) fewer than 0.5% of a sample of points are"
             : "; no knn up to 16 times this one avoids it";
    warnings.push_back(w);
  }
}

PcqmDirection direction(const ColoredCloud& iterated, const ColoredCloud& other,
                        const std::string& iterated_name, const PcqmOptions& o,
                        const Lab2000hlTable& table, std::vector<std::string>& warnings,
                        std::string label, ProgressSteps& progress) {
  detail::DirectionParams params;
  params.max_dim = max_dim(iterated, o.bbox, iterated_name, warnings);
  params.radius_rel = o.radius_rel;
  params.radius_factor = o.radius_factor;
  params.knn = static_cast<std::size_t>(o.knn);
  params.threads = o.threads;
  params.progress = &progress;
  params.label = std::move(label);
  const detail::DirectionOutput out = detail::compute_direction(iterated, other, params, table);
  warn_of_underdetermined_fits(out, iterated.size(), iterated_name, o, warnings);

  PcqmDirection d;
  d.features = out.pooled;
  d.score = o.model.apply(d.features);
  d.bbox_max_side = params.max_dim;
  if (o.per_point) {
    d.per_point.resize(out.features.size());
    for (std::size_t i = 0; i < out.features.size(); ++i) {
      d.per_point[i] = o.model.apply(out.features[i]);
    }
  }
  return d;
}

}  // namespace

PcqmResult compute_pcqm(const ColoredCloud& reference, const ColoredCloud& distorted,
                        const PcqmOptions& options) {
  validate(options);
  validate(reference, "reference");
  validate(distorted, "distorted");
  const auto table = Lab2000hlTable::shared(resolve_data_dir(options.data_dir));

  ProgressSteps progress(options.progress,
                         (options.symmetric ? 2 : 1) * detail::kProgressSteps);
  PcqmResult result;
  result.ref_to_dist = direction(reference, distorted, "reference", options, *table,
                                 result.warnings, "ref→dist", progress);
  result.score = result.ref_to_dist.score;
  if (options.symmetric) {
    result.dist_to_ref = direction(distorted, reference, "distorted", options, *table,
                                   result.warnings, "dist→ref", progress);
    result.score = 0.5 * (result.ref_to_dist.score + result.dist_to_ref->score);
  }
  progress.finish();
  return result;
}

}  // namespace qm3d::pointcloud
