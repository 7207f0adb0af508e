// Gaussian-weighted statistics of paired samples (an element's neighbourhood and its image on the
// other object), with the conventions of each reference implementation.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

namespace qm3d {

/// The constant factor of gaussian_weight, 1 / (sigma sqrt(2 * 3.141592)) (also used by
/// gaussian_weights_in_place). The truncated pi is the references' (MEPP2 cmdm.h, PCQM
/// main.cpp); the constant cancels because every statistic is normalised by the sum of weights.
inline double gaussian_weight_scale(double sigma) {
  // Written as in MEPP2 cmdm.h and PCQM main.cpp so that the weights round the same way.
  return 1.0 / sigma / std::sqrt(2 * 3.141592);
}

/// The Gaussian weight of a squared distance s = d^2: exp(-s / (2 sigma^2)) times
/// gaussian_weight_scale, written -s / 2.0 / sigma / sigma as in the references.
inline double gaussian_weight_from_square(double squared, double sigma) {
  return gaussian_weight_scale(sigma) * std::exp(-squared / 2.0 / sigma / sigma);
}

/// Gaussian weight G(d) = exp(-d^2 / (2 sigma^2)) / (sigma sqrt(2 * 3.141592)).
/// Inline: it runs once per sample.
inline double gaussian_weight(double distance, double sigma) {
  return gaussian_weight_from_square(distance * distance, sigma);
}

/// gaussian_weight(values[i], sigma) for each i, in place: values are distances on entry,
/// weights on return. The exponent and the scaling are the very operations of gaussian_weight;
/// the exponential is glibc's vector exp (libmvec, 4 lanes with AVX2) where the machine has it,
/// which differs from std::exp by at most 4 ulp (CMDM and PCQM scores by about 1e-16 relative)
/// and gives each element the same value wherever it stands in the array and whatever n is.
/// Elsewhere (no AVX2, no libmvec) it is std::exp, and gaussian_weight's value exactly.
void gaussian_weights_in_place(double* values, std::size_t n, double sigma);

/// The same from squared distances: values[i] = s holds d^2 on entry and becomes the weight with
/// the exponent -s / 2.0 / sigma / sigma. A caller that has |x|^2 saves the square root d and
/// its square d * d, which give back |x|^2 only to rounding (so the weight may differ from
/// gaussian_weight(sqrt(s), sigma) in its last bits).
void gaussian_weights_from_squares_in_place(double* values, std::size_t n, double sigma);

/// Which weights the cross term sigma_12 uses, and how it is normalised.
enum class CovarianceWeighting {
  kFirst,  ///< sum w1 (x1 - mu1)(x2 - mu2) / sum w1   (CMDM, PCQM)
  kMixed,  ///< sum w2 (x1 - mu1)(x2 - mu2) / sum w1   (MSDM2, SPEC-CMDM 2)
};

struct CovarianceConvention {
  CovarianceWeighting weighting = CovarianceWeighting::kFirst;
  bool clamp_at_zero = false;  ///< sigma_12 <- max(sigma_12, 0)  (CMDM)
};

/// Means, standard deviations and covariance of two paired sample sets.
struct PairedMoments {
  double mean1 = 0;
  double mean2 = 0;
  double sd1 = 0;
  double sd2 = 0;
  double cov12 = 0;
};

/// Gaussian-weighted moments with biased normalisation: mean_k = sum w_k x_k / sum w_k,
/// sd_k = sqrt(sum w_k (x_k - mean_k)^2 / sum w_k), and the cross term per `convention`.
/// x1, x2, w1, w2 have the same, non-zero length.
PairedMoments weighted_moments(const std::vector<double>& x1, const std::vector<double>& x2,
                               const std::vector<double>& w1, const std::vector<double>& w2,
                               const CovarianceConvention& convention);

/// weighted_moments given its first pass: the sums of w1, w2, x1 w1 and x2 w2 (each accumulated
/// in sample order, as weighted_moments does). The same values, bit for bit.
PairedMoments weighted_moments_from_sums(const std::vector<double>& x1,
                                         const std::vector<double>& x2,
                                         const std::vector<double>& w1,
                                         const std::vector<double>& w2, double sum_w1,
                                         double sum_w2, double sum_x1, double sum_x2,
                                         const CovarianceConvention& convention);

/// weighted_moments_from_sums' last step, given its means (sum x_k w_k / sum w_k) and its second
/// pass's sums in sample order: var_k = sum w_k (x_k - mean_k)^2 (as `w * d * d`), cross = the
/// convention's sum of w (x1 - mean1)(x2 - mean2) (as `w * d1 * d2`). The same operations.
PairedMoments weighted_moments_finish(double mean1, double mean2, double var1, double var2,
                                      double cross, double sum_w1, double sum_w2,
                                      const CovarianceConvention& convention);

/// Unweighted moments (divide by n), covariance not clamped: PCQM's lightness structure.
PairedMoments unweighted_moments(const std::vector<double>& x1, const std::vector<double>& x2);

/// unweighted_moments' last step, given its means (sum x_k / n) and its second pass's sums in
/// sample order (sum (x_k - mean_k)^2, sum (x1 - mean1)(x2 - mean2)). The same operations.
PairedMoments unweighted_moments_finish(double mean1, double mean2, double var1, double var2,
                                        double cross, double n);

/// Population standard deviation sqrt(sum (x - mean)^2 / n), summed in order.
double population_sd(const std::vector<double>& x, double mean);

/// sum w x / sum w.
double weighted_mean(const std::vector<double>& x, const std::vector<double>& w);

}  // namespace qm3d
