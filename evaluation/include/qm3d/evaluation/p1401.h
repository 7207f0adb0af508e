// The statistics of ITU-T P.1401 (07/2012, unchanged in 01/2020) "Methods, metrics and procedures
// for statistical evaluation, qualification and comparison of objective quality prediction
// models": the mapping of objective scores to the MOS scale, rmse with N - d degrees of freedom,
// the epsilon-insensitive rmse*, the outlier ratio and the Pearson correlation with their
// analytic 95 % confidence intervals, and the significance tests between two models evaluated on
// the same subjective data. Clause numbers are those of the 2020 edition (7.3.3 mapping, 7.4 MOS
// uncertainty, 7.5.1 rmse, 7.5.2.2 outlier ratio, 7.5.3 Pearson, 7.6.1 / 7.6.2 / 7.6.4 tests,
// 7.7 rmse*); the 2012 edition has the same clauses 7.3 - 7.7.
//
// Example:
//   const qm3d::MappingFit fit = qm3d::fit_mapping(scores, mos, qm3d::Mapping::cubic);
//   const qm3d::P1401Statistics s =
//       qm3d::p1401_statistics(fit.predicted, mos, fit.parameter_count, mos_ci95);
//   // s.rmse.value, s.rmse.ci->low, s.rmse_star->value, s.outlier_ratio->ci->high ...
//   const qm3d::SignificanceTest t = qm3d::compare_rmse(s.rmse.value, s.degrees_of_freedom,
//                                                       other.rmse.value,
//                                                       other.degrees_of_freedom);
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "qm3d/evaluation/evaluation.h"

namespace qm3d::evaluation {

// ---- mappings (P.1401 §7.3.3, Appendices I and II) ------------------------------------------

/// The function that maps objective scores onto the MOS scale before rmse, rmse* and the outlier
/// ratio are computed (P.1401 §7.3.3: "compensation for the variance between subjective
/// experiments"). Parameter counts d (P.1401 §7.5.1) in brackets.
enum class Mapping {
  none,       ///< identity f(x) = x [d = 0: nothing is estimated from the data]
  linear,     ///< first order, f(x) = a x + b, least squares [d = 2] (P.1401 Appendix II)
  cubic,      ///< third order, monotonic over [min x, max x], least squares [d = 4] (§7.3.3)
  logistic4,  ///< VQEG 4-parameter logistic, LogisticFunction / fit_logistic() [d = 4]
  logistic5,  ///< 5-parameter logistic with a linear term (VQEG FR-TV Phase I; LIVE) [d = 5]
};

/// "none", "linear", "cubic", "logistic4", "logistic5".
std::string_view mapping_name(Mapping mapping);

/// The mapping called `name` (one of mapping_name()'s).
/// @throws std::invalid_argument  an unknown name (the message lists the known ones)
Mapping parse_mapping(std::string_view name);

/// d, the number of parameters the mapping estimates from the data: P.1401 §7.5.1 divides the
/// squared errors by N - d, d the degrees of freedom of the mapping function (4 for its third-order
/// mapping). With no mapping nothing is estimated, so d = 0 here; implementations that use d = 1
/// then (e.g. the default of getRmse in the IoSR MATLAB toolbox) can pass 1 to
/// p1401_statistics().
std::size_t mapping_parameter_count(Mapping mapping);

/// A fitted mapping. `parameters` (MOS and score units) by mapping:
///   none:      {}
///   linear:    {a, b}                  f(x) = a x + b
///   cubic:     {a0, a1, a2, a3}        f(x) = a0 + a1 x + a2 x^2 + a3 x^3 (numpy.polyfit's
///                                      coefficients in reverse order)
///   logistic4: {beta1, beta2, beta3, beta4}  as LogisticFunction
///   logistic5: {b1, b2, b3, b4, b5}    f(x) = b1 (1/2 - 1/(1 + exp(b2 (x - b3)))) + b4 x + b5
/// \bug cubic: `parameters` are expanded from the polynomial fitted in the centred variable
///      t = (x - mid-range) / half-range, so for scores whose range is tiny against their
///      magnitude (e.g. 1000.0 .. 1000.1) f(x) loses digits; `MappingFit::predicted` does not.
struct MappingFunction {
  Mapping mapping = Mapping::none;
  std::vector<double> parameters;
  double operator()(double x) const;
};

struct MappingFit {
  MappingFunction function;
  std::size_t parameter_count = 0;  ///< d (mapping_parameter_count)
  std::vector<double> predicted;    ///< #n f(x_i), the objective MOS predictions (MOSp)
  /// logistic4 / logistic5: MINPACK reported convergence (see LogisticFit); always true for the
  /// closed-form mappings.
  bool converged = true;
  /// logistic4 / logistic5: stopped at the edge of the meaningful region (see
  /// LogisticFit::bounded).
  bool bounded = false;
  /// cubic: the unconstrained least-squares cubic was not monotonic over [min x, max x], and the
  /// constrained solution (see fit_mapping) is reported.
  bool constrained = false;
};

/// Least-squares fit of `mapping` from scores x to MOS y. Deterministic.
///  - linear: ordinary least squares.
///  - cubic: least squares y ~ c0 + c1 t + c2 t^2 + c3 t^3 in t = (x - mid) / half in [-1, 1]
///    (mid and half of the range of x). When its derivative changes sign on [-1, 1], the least
///    squares over the monotonic cubics instead (P.1401 §7.3.3 requires a monotonic mapping).
///    The cubics with s f'(t) >= 0 on [-1, 1] form a convex cone for s = +1 and for s = -1, so
///    the constrained optimum lies on a cone's boundary, where f' vanishes at t = -1, at t = +1,
///    at both (f' = 3 c3 (t^2 - 1)), or doubly inside (f = c0 + k (t - t0)^3, monotonic for every
///    k). Each family is a linear least-squares problem (the last one for each t0: t0 is scanned
///    over 2001 points of [-1, 1] and refined by golden-section search); the candidates that are
///    monotonic are kept and the one with the least sum of squares wins. (The scan can miss a
///    second, deeper local minimum of the residual in t0 only if it is narrower than 0.001.)
///  - logistic4: fit_logistic().
///  - logistic5: Levenberg-Marquardt on standardised data (as fit_logistic), started from the
///    logistic4 optimum (b4 = 0: the 5-parameter curve is then never worse than the 4-parameter
///    one) and from the three logistic4 starting scales.
/// @param[in] x  #n objective scores;  @param[in] y  #n MOS
/// @throws NumericError  n <= d, a non-finite value, constant x (linear, cubic, logistics),
///                       fewer than 4 distinct x (cubic), or a logistic fit failing
/// @throws std::invalid_argument  x and y differ in length
MappingFit fit_mapping(const std::vector<double>& x, const std::vector<double>& y, Mapping mapping,
                       const LogisticFitOptions& options = {});

// ---- statistics of one model (P.1401 §7.4, §7.5, §7.7) --------------------------------------

/// Each value with its analytic 95 % interval in `ci` (absent only for an undefined PLCC).
struct P1401Statistics {
  std::size_t count = 0;               ///< N
  std::size_t parameter_count = 0;     ///< d
  std::size_t degrees_of_freedom = 0;  ///< N - d
  /// Pearson(MOSp, MOS); ci: Fisher z, tanh(atanh r -+ 1.96 / sqrt(N - 3)) (§7.5.3); absent
  /// ci when N <= 3.
  Statistic plcc;
  /// sqrt(sum (MOS - MOSp)^2 / (N - d)) (§7.5.1); ci: rmse sqrt(N - d) / sqrt(chi2_q(N - d)) for
  /// q = 0.975 (low) and 0.025 (high), chi2_q the q-quantile of chi-square with N - d dof.
  Statistic rmse;
  /// With ci95 only: sqrt(sum max(0, |MOS - MOSp| - ci95)^2 / (N - d)) (§7.7); ci: the same
  /// chi-square form as rmse (P.1401 §7.7 tests rmse* with the F-test of rmse, i.e. under the
  /// same distributional assumption).
  std::optional<Statistic> rmse_star;
  /// With ci95 only: fraction of stimuli with |MOS - MOSp| > ci95 (§7.5.2.2); ci: OR -+ 1.96
  /// sqrt(OR (1 - OR) / N), clamped to [0, 1] (normal approximation of the binomial).
  std::optional<Statistic> outlier_ratio;
  std::size_t outliers = 0;  ///< the numerator of outlier_ratio
};

/// P.1401 statistics of predictions against MOS.
/// @param[in] predicted        #n MOSp = f(x_i), e.g. MappingFit::predicted
/// @param[in] mos              #n MOS
/// @param[in] parameter_count  d of the mapping that produced `predicted`
/// @param[in] mos_ci95         #n half-widths of the MOS 95 % intervals (§7.4, mos_ci95()), or
///                             empty (no rmse*, no outlier ratio)
/// @throws NumericError  N <= d, a non-finite value, a negative or non-finite ci95
/// @throws std::invalid_argument  lengths differ
P1401Statistics p1401_statistics(const std::vector<double>& predicted,
                                 const std::vector<double>& mos, std::size_t parameter_count,
                                 const std::vector<double>& mos_ci95 = {});

/// The P.1401 §7.5.3 interval of a Pearson correlation r over n pairs: tanh(atanh r -+ 1.96 /
/// sqrt(n - 3)); absent when n <= 3 or r is NaN.
std::optional<Interval> correlation_interval(double r, std::size_t n);

/// A mapping fitted to one model's scores and the statistics of its predictions.
struct P1401Evaluation {
  MappingFit fit;
  P1401Statistics statistics;
};

/// fit_mapping(scores, mos, mapping), then p1401_statistics(fit.predicted, mos, d, mos_ci95).
P1401Evaluation evaluate_p1401(const std::vector<double>& scores, const std::vector<double>& mos,
                               Mapping mapping, const std::vector<double>& mos_ci95 = {},
                               const LogisticFitOptions& options = {});

/// Half-width of the 95 % interval of one MOS from the standard deviation of its M votes
/// (P.1401 §7.4, Appendix III): t(0.975, M - 1) sd / sqrt(M), t the Student quantile (P.1401's
/// "t(0.05, M)", two-tailed).
/// @throws NumericError  votes < 2, sd negative or not finite
double mos_ci95(double sd, std::size_t votes);

// ---- significance of the difference between two models (P.1401 §7.6, §7.7) -------------------

/// A test statistic and its p-value: P.1401 calls the difference significant at the 95 % level
/// exactly when p < 0.05.
struct SignificanceTest {
  double statistic = 0;
  double p = 1;
};

/// §7.6.1: z = (atanh r1 - atanh r2) / sqrt(1 / (n1 - 3) + 1 / (n2 - 3)), two-sided normal p =
/// erfc(|z| / sqrt 2). P.1401 uses this independent-samples form also when both models are
/// evaluated on the same stimuli; it then ignores the correlation between the two models, which
/// makes the test conservative for positively correlated models. |r| = 1 is clamped to
/// 1 - 1e-15 so that z stays finite.
/// @throws NumericError  n1 or n2 <= 3, r outside [-1, 1] or not finite
SignificanceTest compare_correlations(double r1, std::size_t n1, double r2, std::size_t n2);

/// §7.6.4 (and §7.7 for rmse*): F = rmse_larger^2 / rmse_smaller^2 with (dof_larger,
/// dof_smaller) degrees of freedom (dof = N - d); p = P(F' > F), the upper tail of the F
/// distribution (P.1401 rejects equality when F > F_0.05(dof_larger, dof_smaller), i.e. p < 0.05;
/// the two-sided p of the equal-variance test would be min(1, 2 p)). F = 1, p = 1 when both
/// are 0.
/// @throws NumericError  a dof of 0, an rmse negative or not finite, exactly one rmse 0
SignificanceTest compare_rmse(double rmse1, std::size_t dof1, double rmse2, std::size_t dof2);

/// §7.6.2: pooled p = (n1 or1 + n2 or2) / (n1 + n2), z = (or1 - or2) / sqrt(p (1 - p) (1/n1 +
/// 1/n2)), two-sided normal p. z = 0, p = 1 when the pooled proportion is 0 or 1.
/// @throws NumericError  n1 or n2 = 0, a ratio outside [0, 1] or not finite
SignificanceTest compare_outlier_ratios(double or1, std::size_t n1, double or2, std::size_t n2);

/// Every P.1401 test between two models' statistics (computed on the same subjective data).
struct P1401Comparison {
  SignificanceTest plcc;                          ///< compare_correlations (§7.6.1)
  SignificanceTest rmse;                          ///< compare_rmse (§7.6.4)
  std::optional<SignificanceTest> rmse_star;      ///< compare_rmse on rmse* (§7.7)
  std::optional<SignificanceTest> outlier_ratio;  ///< compare_outlier_ratios (§7.6.2)
};

/// The tests between `a` and `b` (statistics signed a - b); rmse_star and outlier_ratio when
/// both have them.
/// @throws NumericError  as the individual tests (e.g. N <= 3, or an undefined PLCC)
P1401Comparison compare_p1401(const P1401Statistics& a, const P1401Statistics& b);

// ---- distribution functions (for the intervals and tests above) ------------------------------

/// P(Z > z) for a standard normal Z: erfc(z / sqrt 2) / 2 (full relative precision in the upper
/// tail down to the smallest doubles).
double normal_sf(double z);

/// 2 P(Z > |z|) = erfc(|z| / sqrt 2), the two-sided p of a z statistic, without the
/// cancellation of 2 (1 - Phi(|z|)): tiny but non-zero where 1 - Phi underflows.
double two_sided_normal_p(double z);

/// Regularized lower incomplete gamma P(a, x) = gamma(a, x) / Gamma(a), by its series for
/// x < a + 1 and 1 - Q otherwise (Numerical Recipes, 3rd ed., §6.2).
/// @throws NumericError  a <= 0, x < 0, or not finite
double regularized_gamma_p(double a, double x);

/// Regularized upper incomplete gamma Q(a, x) = 1 - P(a, x), by the Legendre continued
/// fraction (modified Lentz) for x >= a + 1 and 1 - P otherwise: each tail is computed directly
/// where it is the small one.
double regularized_gamma_q(double a, double x);

/// The p-quantile of the chi-square distribution with `dof` degrees of freedom (scipy's
/// chi2.ppf): 2 P^-1(dof / 2, p), by Newton's method on u = log x applied to log P(a, e^u) =
/// log p for p <= 0.5 and to log Q(a, e^u) = log(1 - p) above (each tail where it is small, so
/// extreme tails keep their digits), inside a bracket of u found by doubling steps from x = a
/// (bisection wherever a Newton step would leave the bracket).
/// @throws NumericError  dof <= 0, p outside (0, 1)
double chi_square_quantile(double p, double dof);

/// Regularized incomplete beta I_x(a, b), by its continued fraction (modified Lentz), on
/// I_x(a, b) for x < (a + 1) / (a + b + 2) and 1 - I_{1-x}(b, a) above (Numerical Recipes,
/// 3rd ed., §6.4).
/// @throws NumericError  a or b <= 0, x outside [0, 1], or not finite
double regularized_beta(double x, double a, double b);

/// P(F' > f) for F' ~ F(d1, d2) (scipy's f.sf): I_{d2 / (d2 + d1 f)}(d2 / 2, d1 / 2).
double f_sf(double f, double d1, double d2);

/// P(T > t) for T ~ Student t with `dof` degrees of freedom: I_{dof/(dof+t^2)}(dof/2, 1/2) / 2
/// for t >= 0.
double student_t_sf(double t, double dof);

/// The p-quantile of Student's t (scipy's t.ppf), by bisection on student_t_sf.
double student_t_quantile(double p, double dof);

}  // namespace qm3d::evaluation
