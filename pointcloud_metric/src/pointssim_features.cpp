// PointSSIM's quantities and estimators (pointssim_internal.h): the reference's pointssim.m and
// feature_map.m (mmspg/pointssim @ 2358dd3), with the Octave functions it ran on, as
// ../shared/docs/SPEC-POINTSSIM.md describes them. Sums run in index order, as those functions
// sum.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "pointssim_internal.h"

namespace qm3d::pointcloud::detail {
namespace {

constexpr int kChunk = 1024;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;
/// BT.709 luma weights and offset of the reference's rgb_to_yuv (its U and V are unused).
constexpr double kLumaR = 0.2126, kLumaG = 0.7152, kLumaB = 0.0722, kLumaOffset = 0;
/// The quartiles of QCD.
constexpr double kLowerQuartile = 0.25, kUpperQuartile = 0.75;

int thread_count(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

double mean(const double* q, std::size_t m) {
  double sum = 0;
  for (std::size_t i = 0; i < m; ++i) sum += q[i];
  return sum / static_cast<double>(m);
}

// var(q) with N - 1: the sum of squared deviations from the mean over m - 1 (0 for one value).
double variance(const double* q, std::size_t m) {
  if (m == 1) return std::isnan(q[0]) ? kNan : 0.0;
  const double mu = mean(q, m);
  double sum = 0;
  for (std::size_t i = 0; i < m; ++i) sum += (q[i] - mu) * (q[i] - mu);
  return sum / static_cast<double>(m - 1);
}

bool has_nan(const double* q, std::size_t m) {
  return std::any_of(q, q + m, [](double v) { return std::isnan(v); });
}

// The median of `v` (sorted in place): the middle value, or the two middle ones' sum / 2
// (Octave's median); NaN when any value is NaN.
double median_in_place(std::vector<double>& v) {
  if (has_nan(v.data(), v.size())) return kNan;
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size(), k = (m + 1) / 2;  // k 1-based
  return m % 2 == 1 ? v[k - 1] : (v[k - 1] + v[k]) / 2;
}

// quantile(q, p), MATLAB's method (Octave method 5) over the non-NaN values of sorted `x`:
// position p m + 0.5, clamped to [1, m - 1], linear between the two values around it.
double quantile(const std::vector<double>& x, double p) {
  const std::size_t m = x.size();
  if (m == 0) return kNan;
  const double position = p * static_cast<double>(m) + 0.5;
  const double low = std::max(std::min(std::floor(position), static_cast<double>(m) - 1), 1.0);
  const double fraction = std::max(std::min(position - low, 1.0), 0.0);
  const auto i = static_cast<std::size_t>(low) - 1;
  const double next = m == 1 ? x[i] : x[i + 1];  // one value: it is duplicated
  return (1 - fraction) * x[i] + fraction * next;
}

double quartile_dispersion(const double* q, std::size_t m, std::vector<double>& scratch) {
  scratch.clear();
  for (std::size_t i = 0; i < m; ++i) {
    if (!std::isnan(q[i])) scratch.push_back(q[i]);
  }
  std::sort(scratch.begin(), scratch.end());
  const double q1 = quantile(scratch, kLowerQuartile), q3 = quantile(scratch, kUpperQuartile);
  return (q3 - q1) / (q3 + q1);
}

// The mean (or median) absolute deviation from the mean (median).
double mean_absolute_deviation(const double* q, std::size_t m) {
  const double mu = mean(q, m);
  double sum = 0;
  for (std::size_t i = 0; i < m; ++i) sum += std::abs(q[i] - mu);
  return sum / static_cast<double>(m);
}

double median_absolute_deviation(const double* q, std::size_t m, std::vector<double>& scratch) {
  scratch.assign(q, q + m);
  const double centre = median_in_place(scratch);
  for (std::size_t i = 0; i < m; ++i) scratch[i] = std::abs(q[i] - centre);
  return median_in_place(scratch);
}

std::uint8_t luma(const std::array<std::uint8_t, 3>& rgb) {
  // uint8(round(.)): round half away from zero, saturated.
  const double y = ((kLumaR * rgb[0] + kLumaG * rgb[1]) + kLumaB * rgb[2]) + kLumaOffset;
  return static_cast<std::uint8_t>(std::min(std::round(y), 255.0));
}

// The angular similarity of two normals: real(1 - 2 acos(|a.b| / (|a| |b|)) / pi); a cosine
// above 1 from rounding gives 1, as real(acos(c)) = 0 does.
double normal_similarity(const Vec3& a, const Vec3& b) {
  const double dot = (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2];
  const double na = std::sqrt((a[0] * a[0] + a[1] * a[1]) + a[2] * a[2]);
  const double nb = std::sqrt((b[0] * b[0] + b[1] * b[1]) + b[2] * b[2]);
  const double c = std::abs(dot) / (na * nb);
  if (std::isnan(c)) return kNan;
  return 1 - 2 * std::acos(std::min(c, 1.0)) / kPi;
}

/// What the quantities of a row are made of.
struct Sources {
  const SsimCloud& cloud;
  const SurfaceEstimates* surface;
  const std::vector<std::uint8_t>& lumas;
};

// The quantities of attribute `a` over the neighbours `nb` of row `row` (nb[0] is the row).
void quantities(PointssimAttribute a, const Sources& s, std::size_t row,
                const std::vector<Neighbour>& nb, std::vector<double>& q) {
  q.clear();
  switch (a) {
    case PointssimAttribute::kGeom:
      for (std::size_t j = 1; j < nb.size(); ++j) q.push_back(std::sqrt(nb[j].distance2));
      break;
    case PointssimAttribute::kNorm:
      for (std::size_t j = 1; j < nb.size(); ++j) {
        q.push_back(normal_similarity(s.surface->normals[nb[j].index], s.surface->normals[row]));
      }
      break;
    case PointssimAttribute::kCurv:
      for (const Neighbour& n : nb) q.push_back(s.surface->curvatures[n.index]);
      break;
    case PointssimAttribute::kColor:
      for (const Neighbour& n : nb) q.push_back(s.lumas[n.index]);
      break;
  }
}

}  // namespace

double estimate(PointssimEstimator e, const double* q, std::size_t m,
                std::vector<double>& scratch) {
  switch (e) {
    case PointssimEstimator::kStd:
      return std::sqrt(variance(q, m));
    case PointssimEstimator::kVar:
      return variance(q, m);
    case PointssimEstimator::kMeanAd:
      return mean_absolute_deviation(q, m);
    case PointssimEstimator::kMedianAd:
      return median_absolute_deviation(q, m, scratch);
    case PointssimEstimator::kCov:
      return std::sqrt(variance(q, m)) / mean(q, m);
    case PointssimEstimator::kQcd:
      return quartile_dispersion(q, m, scratch);
    case PointssimEstimator::kMean:
      return mean(q, m);
  }
  return kNan;
}

FeatureMaps feature_maps(const SsimCloud& cloud, const OrderedSearch& search,
                         const SurfaceEstimates* surface, std::size_t k,
                         const std::vector<PointssimAttribute>& attributes,
                         const std::vector<PointssimEstimator>& estimators, int threads) {
  const std::size_t n = cloud.points.size();
  std::vector<std::uint8_t> lumas(cloud.colours.size());
  for (std::size_t i = 0; i < lumas.size(); ++i) lumas[i] = luma(cloud.colours[i]);
  const Sources sources{cloud, surface, lumas};
  FeatureMaps out;
  out.maps.assign(attributes.size() * estimators.size(), std::vector<double>(n));
  const bool kept = surface != nullptr && surface->k == k && !surface->nearest.empty();
#pragma omp parallel num_threads(thread_count(threads))
  {
    std::vector<Neighbour> nb;
    std::vector<double> q, scratch;
#pragma omp for schedule(dynamic, kChunk)
    for (long i = 0; i < static_cast<long>(n); ++i) {
      const auto row = static_cast<std::size_t>(i);
      if (kept) {
        // The fit's neighbours, with their squared distances as the search computes them.
        nb.resize(k);
        for (std::size_t j = 0; j < k; ++j) {
          const std::uint32_t r = surface->nearest[row * k + j];
          nb[j] = {squared_distance(cloud.points[row], cloud.points[r]), r};
        }
      } else {
        search.knn(cloud.points[row], k, nb);
      }
      for (std::size_t a = 0; a < attributes.size(); ++a) {
        quantities(attributes[a], sources, row, nb, q);
        for (std::size_t e = 0; e < estimators.size(); ++e) {
          out.maps[a * estimators.size() + e][row] =
              estimate(estimators[e], q.data(), q.size(), scratch);
        }
      }
    }
  }
  return out;
}

}  // namespace qm3d::pointcloud::detail
