// How well objective scores predict subjective ones (MOS): the statistics of ITU-T P.1401 (2020)
// and of the VQEG reports (FR-TV Phase II, 2003) — Pearson (plain, and after the monotonic
// logistic mapping), Spearman, Kendall, RMSE and outlier ratio after the mapping — with
// bootstrap confidence intervals.
//
// Example:
//   const qm3d::EvaluationResult r = qm3d::evaluate_scores(scores, mos);
//   // r.plcc.value, r.srocc.value, r.plcc_logistic.ci->low, r.fit.function(0.02) ...
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace qm3d::evaluation {

/// Pearson linear correlation coefficient; sums in element order. NaN when there are fewer
/// than 2 pairs or one variable is constant.
/// @throws std::invalid_argument  x and y differ in length
double pearson(const std::vector<double>& x, const std::vector<double>& y);

/// Ranks 1..n of `values`; tied values share the average of their ranks ({10, 20, 20, 30} ->
/// {1, 2.5, 2.5, 4}).
std::vector<double> average_ranks(const std::vector<double>& values);

/// Spearman rank correlation: Pearson of the average ranks (so ties are handled exactly).
double spearman(const std::vector<double>& x, const std::vector<double>& y);

/// Kendall tau-b (ties in either variable corrected), by Knight's O(n log n) algorithm
/// (W. R. Knight, "A computer method for calculating Kendall's tau with ungrouped data",
/// JASA 1966). NaN when either variable is constant or there are fewer than 2 pairs.
double kendall_tau_b(const std::vector<double>& x, const std::vector<double>& y);

/// The VQEG 4-parameter logistic (VQEG FR-TV Phase II, eq. 1), a monotonic mapping as ITU-T
/// P.1401 §7.3.3 asks for:
/// f(x) = beta2 + (beta1 - beta2) / (1 + exp(-(x - beta3) / |beta4|)).
/// Monotonic in x for every parameter value: beta2 as x -> -inf, beta1 as x -> +inf.
struct LogisticFunction {
  double beta1 = 1;  ///< value for x -> +inf (MOS units)
  double beta2 = 0;  ///< value for x -> -inf (MOS units)
  double beta3 = 0;  ///< centre (score units)
  double beta4 = 1;  ///< scale (score units); only |beta4| is used
  double operator()(double x) const;
};

struct LogisticFitOptions {
  /// Function evaluations allowed to each Levenberg-Marquardt start.
  int max_evaluations = 2000;
  /// Relative tolerance on the parameters and the sum of squares (MINPACK xtol and ftol; this
  /// is MINPACK's recommended sqrt(machine epsilon)).
  double tolerance = 1.4901161193847656e-08;
};

struct LogisticFit {
  LogisticFunction function;
  double rmse = 0;         ///< sqrt(mean((f(x) - y)^2)) at the optimum
  bool converged = false;  ///< MINPACK reported convergence (not the evaluation limit)
  /// Stopped at the edge of the meaningful region: an asymptote beyond 10 standard deviations
  /// of y (the relation is practically linear over the data), or a scale below 0.01 standard
  /// deviations of x (the curve is a step: no trend). The curve found is then as good as the
  /// unbounded optimum for every practical purpose.
  bool bounded = false;
  int evaluations = 0;  ///< function evaluations of the retained start
};

/// Least-squares fit of the logistic mapping y ~ f(x) by Levenberg-Marquardt (Eigen's MINPACK
/// port, unsupported/NonLinearOptimization) with the analytic Jacobian, on standardised x and y.
/// Starts: beta1/beta2 at the extreme y in the direction of the Pearson sign, beta3 at the median
/// x, |beta4| at 0.3, 1 and 3 standard deviations of x; the start with the lowest residual wins.
/// @param[in] x  #n scores;  @param[in] y  #n subjective scores
/// @throws NumericError  fewer than 5 pairs, a non-finite value, constant x or y, or no start
///                       reaches a finite optimum
LogisticFit fit_logistic(const std::vector<double>& x, const std::vector<double>& y,
                         const LogisticFitOptions& options = {});

/// sqrt(mean((predicted - observed)^2)).
double root_mean_square_error(const std::vector<double>& predicted,
                              const std::vector<double>& observed);

/// ITU-T P.1401 §7.5.2.2 outlier ratio: the fraction of stimuli whose prediction error
/// |predicted - mos| exceeds the half-width of the MOS 95% confidence interval.
/// @param[in] ci95  #n half-widths of the 95% confidence intervals of the MOS (>= 0)
double outlier_ratio(const std::vector<double>& predicted, const std::vector<double>& mos,
                     const std::vector<double>& ci95);

/// Most bootstrap replicates evaluate_scores() accepts: 100 times the usual 1000 (percentile
/// intervals stop changing long before), and each replicate refits the logistic, so more would
/// only run for hours (a negative count read as unsigned wraps round to ~1.8e19).
inline constexpr std::size_t kMaxBootstrapReplicates = 100000;

struct EvaluationOptions {
  /// Bootstrap replicates (pairs resampled with replacement); 0 = no intervals; at most
  /// kMaxBootstrapReplicates.
  std::size_t bootstrap = 1000;
  /// Seed of the std::mt19937_64 that draws the replicates (fully specified by the standard,
  /// so the intervals are the same on every platform).
  std::uint64_t seed = 1;
  /// Coverage of the percentile intervals.
  double confidence = 0.95;
  LogisticFitOptions fit;
  /// True: fewer than 5 stimuli (too few for the logistic fit) is an error. False (the
  /// evaluation protocol, which maps with its own function): from 3 stimuli on, the
  /// correlations alone, the logistic statistics NaN without interval.
  bool require_logistic = true;
};

/// A confidence interval: percentile bootstrap here, analytic in p1401.h.
struct Interval {
  double low = 0;
  double high = 0;
};

struct Statistic {
  double value = 0;
  /// absent when EvaluationOptions::bootstrap == 0 (evaluate_scores) or undefined (p1401.h)
  std::optional<Interval> ci;
};

struct EvaluationResult {
  std::size_t count = 0;                   ///< number of (score, MOS) pairs
  Statistic plcc;                          ///< Pearson(score, MOS), no mapping
  Statistic srocc;                         ///< Spearman(score, MOS)
  Statistic krocc;                         ///< Kendall tau-b(score, MOS)
  Statistic plcc_logistic;                 ///< Pearson(f(score), MOS) after the logistic fit
  Statistic rmse_logistic;                 ///< RMSE of f(score) against MOS (MOS units)
  std::optional<Statistic> outlier_ratio;  ///< only when confidence intervals are given
  LogisticFit fit;                         ///< the mapping fitted on all pairs
  std::size_t bootstrap_replicates = 0;    ///< requested
  std::size_t bootstrap_used = 0;          ///< replicates where every statistic was defined
};

/// Every statistic above for `scores` against `mos`, with percentile bootstrap intervals.
/// Each replicate refits the logistic (started from the full-data fit).
/// @param[in] scores    #n objective scores (any direction: distortions or qualities)
/// @param[in] mos       #n subjective scores
/// @param[in] mos_ci95  #n MOS 95% CI half-widths, or empty (no outlier ratio)
/// @throws NumericError  fewer than 5 pairs, non-finite values, constant scores or MOS
/// @throws std::invalid_argument  lengths differ, confidence not in (0, 1)
EvaluationResult evaluate_scores(const std::vector<double>& scores, const std::vector<double>& mos,
                                 const std::vector<double>& mos_ci95 = {},
                                 const EvaluationOptions& options = {});

}  // namespace qm3d::evaluation
