#include "qm3d/evaluation/evaluation.h"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

#include "least_squares.h"
#include "qm3d/common/error.h"
#include "qm3d/common/pooling.h"
#include "qm3d/common/statistics.h"

namespace qm3d::evaluation {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// Fewest pairs the 4-parameter logistic can be fitted to (one more than its parameters).
constexpr std::size_t kMinPairsForFit = 5;
/// Without the logistic (EvaluationOptions::require_logistic false): PLCC, SROCC and KROCC are
/// defined from 2 stimuli, meaningful (not +-1 by construction) from 3.
constexpr std::size_t kMinStimuliForCorrelations = 3;
/// Starting scales |beta4| of the logistic, in standard deviations of x (a sharp, a medium and a
/// nearly linear mapping); the best optimum is kept.
constexpr std::array<double, 3> kStartScalesSd = {0.3, 1.0, 3.0};

void check_same_length(std::size_t a, std::size_t b, const char* what) {
  if (a != b) {
    throw std::invalid_argument(std::string(what) + ": lengths differ (" + std::to_string(a) +
                                " vs " + std::to_string(b) + ")");
  }
}

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

// Pairs (x_i choose 2) summed over runs of equal values in a sorted sequence.
template <typename Equal>
double tied_pairs(const std::vector<std::size_t>& order, Equal equal) {
  double pairs = 0;
  std::size_t run = 1;
  for (std::size_t i = 1; i <= order.size(); ++i) {
    if (i < order.size() && equal(order[i - 1], order[i])) {
      ++run;
      continue;
    }
    pairs += 0.5 * static_cast<double>(run) * static_cast<double>(run - 1);
    run = 1;
  }
  return pairs;
}

// Sorts `order` by y (stable merge sort) and returns the number of exchanges: the pairs i < j
// with y[order[i]] > y[order[j]] (strictly).
double sort_counting_inversions(std::vector<std::size_t>& order, const std::vector<double>& y) {
  std::vector<std::size_t> buffer(order.size());
  double inversions = 0;
  for (std::size_t width = 1; width < order.size(); width *= 2) {
    for (std::size_t lo = 0; lo < order.size(); lo += 2 * width) {
      const std::size_t mid = std::min(lo + width, order.size());
      const std::size_t hi = std::min(lo + 2 * width, order.size());
      std::size_t i = lo, j = mid, k = lo;
      while (i < mid && j < hi) {
        if (y[order[j]] < y[order[i]]) {
          inversions += static_cast<double>(mid - i);
          buffer[k++] = order[j++];
        } else {
          buffer[k++] = order[i++];
        }
      }
      while (i < mid) buffer[k++] = order[i++];
      while (j < hi) buffer[k++] = order[j++];
    }
    order.swap(buffer);
  }
  return inversions;
}

// ---- logistic fit --------------------------------------------------------------------------

struct Standardised {
  std::vector<double> values;
  double mean = 0;
  double sd = 0;
};

Standardised standardise(const std::vector<double>& v, const char* what) {
  Standardised s;
  s.mean = mean_pool(v);
  s.sd = population_sd(v, s.mean);
  if (!(s.sd > 0)) throw NumericError(std::string("logistic fit: the ") + what + " are constant");
  s.values.reserve(v.size());
  for (double x : v) s.values.push_back((x - s.mean) / s.sd);
  return s;
}

// Parameters in standardised units: (beta1, beta2, beta3, log|beta4|).
Eigen::VectorXd to_standard(const LogisticFunction& f, const Standardised& x,
                            const Standardised& y) {
  Eigen::VectorXd p(4);
  p << (f.beta1 - y.mean) / y.sd, (f.beta2 - y.mean) / y.sd, (f.beta3 - x.mean) / x.sd,
      std::log(std::fabs(f.beta4) / x.sd);
  return p;
}

LogisticFunction from_standard(const Eigen::VectorXd& p, const Standardised& x,
                               const Standardised& y) {
  return {y.mean + y.sd * p[0], y.mean + y.sd * p[1], x.mean + x.sd * p[2], x.sd * std::exp(p[3])};
}

detail::LeastSquaresProblem logistic_problem(const std::vector<double>& u,
                                             const std::vector<double>& v) {
  detail::LeastSquaresProblem problem;
  problem.residuals = static_cast<Eigen::Index>(u.size());
  problem.residual = [&u, &v](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
    const double scale = std::exp(p[3]);
    for (std::size_t i = 0; i < u.size(); ++i) {
      const double s = detail::logistic_sigmoid((u[i] - p[2]) / scale);
      r[static_cast<Eigen::Index>(i)] = p[1] + (p[0] - p[1]) * s - v[i];
    }
  };
  problem.jacobian = [&u](const Eigen::VectorXd& p, Eigen::MatrixXd& jac) {
    const double scale = std::exp(p[3]);
    for (std::size_t i = 0; i < u.size(); ++i) {
      const auto row = static_cast<Eigen::Index>(i);
      const double z = (u[i] - p[2]) / scale;
      const double s = detail::logistic_sigmoid(z);
      const double slope = (p[0] - p[1]) * s * (1 - s);  // d f / d z
      jac(row, 0) = s;
      jac(row, 1) = 1 - s;
      jac(row, 2) = -slope / scale;
      jac(row, 3) = -slope * z;
    }
  };
  problem.admissible = [](const Eigen::VectorXd& p) {
    return detail::logistic_admissible(p[0], p[1], std::exp(p[3]));
  };
  return problem;
}

void check_fit_input(const std::vector<double>& x, const std::vector<double>& y) {
  check_same_length(x.size(), y.size(), "logistic fit");
  if (x.size() < kMinPairsForFit) {
    throw NumericError("logistic fit: " + std::to_string(x.size()) + " pairs, at least " +
                       std::to_string(kMinPairsForFit) + " needed");
  }
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) {
      throw NumericError("logistic fit: non-finite value at pair " + std::to_string(i + 1));
    }
  }
}

// Levenberg-Marquardt from each start (standardised units); the lowest residual wins.
LogisticFit fit_from_starts(const Standardised& x, const Standardised& y,
                            const std::vector<Eigen::VectorXd>& starts,
                            const LogisticFitOptions& options) {
  const detail::LeastSquaresProblem problem = logistic_problem(x.values, y.values);
  detail::LeastSquaresResult best;
  best.sum_squares = std::numeric_limits<double>::infinity();
  for (const Eigen::VectorXd& start : starts) {
    detail::LeastSquaresResult r =
        detail::minimize_least_squares(problem, start, options.max_evaluations, options.tolerance);
    if (r.x.allFinite() && r.sum_squares < best.sum_squares) best = std::move(r);
  }
  if (!std::isfinite(best.sum_squares)) {
    throw NumericError("logistic fit: no start reached a finite optimum");
  }
  LogisticFit fit;
  fit.function = from_standard(best.x, x, y);
  fit.rmse = y.sd * std::sqrt(best.sum_squares / static_cast<double>(x.values.size()));
  fit.converged = best.converged;
  fit.bounded = best.left_region;
  fit.evaluations = best.evaluations;
  return fit;
}

std::vector<Eigen::VectorXd> default_starts(const Standardised& x, const Standardised& y) {
  const bool increasing = !(pearson(x.values, y.values) < 0);
  const auto [lo, hi] = std::minmax_element(y.values.begin(), y.values.end());
  std::vector<Eigen::VectorXd> starts;
  for (double scale : kStartScalesSd) {
    Eigen::VectorXd p(4);
    p << (increasing ? *hi : *lo), (increasing ? *lo : *hi), median_of(x.values), std::log(scale);
    starts.push_back(p);
  }
  return starts;
}

LogisticFit fit_logistic_from(const std::vector<double>& x, const std::vector<double>& y,
                              const LogisticFunction& start, const LogisticFitOptions& options) {
  check_fit_input(x, y);
  const Standardised sx = standardise(x, "scores"), sy = standardise(y, "subjective scores");
  return fit_from_starts(sx, sy, {to_standard(start, sx, sy)}, options);
}

// ---- evaluation and bootstrap --------------------------------------------------------------

// The statistics of one sample, in the order of kStatisticCount below.
constexpr std::size_t kStatisticCount = 6;
constexpr std::size_t kCorrelationCount = 3;  ///< PLCC, SROCC, KROCC come first
using Values = std::array<double, kStatisticCount>;

std::vector<double> mapped(const LogisticFunction& f, const std::vector<double>& x) {
  std::vector<double> out;
  out.reserve(x.size());
  for (double v : x) out.push_back(f(v));
  return out;
}

Values sample_statistics(const std::vector<double>& x, const std::vector<double>& y,
                         const std::vector<double>& ci, const LogisticFit& fit) {
  const std::vector<double> predicted = mapped(fit.function, x);
  return {pearson(x, y),
          spearman(x, y),
          kendall_tau_b(x, y),
          pearson(predicted, y),
          root_mean_square_error(predicted, y),
          ci.empty() ? 0.0 : outlier_ratio(predicted, y, ci)};
}

// Uniform index in [0, n) by rejection (exact, and the same on every standard library).
std::size_t draw_index(std::mt19937_64& rng, std::size_t n) {
  const std::uint64_t range = static_cast<std::uint64_t>(n);
  const std::uint64_t limit =
      std::numeric_limits<std::uint64_t>::max() - std::numeric_limits<std::uint64_t>::max() % range;
  std::uint64_t r = rng();
  while (r >= limit) r = rng();
  return static_cast<std::size_t>(r % range);
}

struct Resample {
  std::vector<double> x, y, ci;
};

Resample draw_resample(std::mt19937_64& rng, const std::vector<double>& x,
                       const std::vector<double>& y, const std::vector<double>& ci) {
  Resample s;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const std::size_t k = draw_index(rng, x.size());
    s.x.push_back(x[k]);
    s.y.push_back(y[k]);
    if (!ci.empty()) s.ci.push_back(ci[k]);
  }
  return s;
}

// The correlations alone (no logistic fit: too few stimuli for one); the rest NaN.
Values correlations(const std::vector<double>& x, const std::vector<double>& y) {
  return {pearson(x, y), spearman(x, y), kendall_tau_b(x, y), kNaN, kNaN, kNaN};
}

// Statistics of every replicate in which all of them are defined (in draw order); without
// `logistic`, the correlations alone.
std::vector<Values> bootstrap_values(const std::vector<double>& x, const std::vector<double>& y,
                                     const std::vector<double>& ci, const LogisticFit& full_fit,
                                     const EvaluationOptions& options, bool logistic) {
  std::mt19937_64 rng(options.seed);
  std::vector<Values> replicates;
  const std::size_t defined = logistic ? kStatisticCount : kCorrelationCount;
  for (std::size_t b = 0; b < options.bootstrap; ++b) {
    const Resample s = draw_resample(rng, x, y, ci);
    try {
      const Values v =
          logistic ? sample_statistics(s.x, s.y, s.ci,
                                       fit_logistic_from(s.x, s.y, full_fit.function, options.fit))
                   : correlations(s.x, s.y);
      if (std::all_of(v.begin(), v.begin() + defined, [](double d) { return std::isfinite(d); })) {
        replicates.push_back(v);
      }
    } catch (const NumericError&) {
      // A degenerate resample (e.g. constant scores): dropped, counted by the caller.
    }
  }
  return replicates;
}

// Linear-interpolation quantile (Hyndman & Fan type 7) of sorted values.
double quantile_sorted(const std::vector<double>& sorted, double p) {
  const double h = p * static_cast<double>(sorted.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (h - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

std::optional<Interval> percentile_interval(const std::vector<Values>& replicates, std::size_t k,
                                            double confidence) {
  if (replicates.empty()) return std::nullopt;
  std::vector<double> v;
  v.reserve(replicates.size());
  for (const Values& r : replicates) v.push_back(r[k]);
  std::sort(v.begin(), v.end());
  const double alpha = 0.5 * (1 - confidence);
  return Interval{quantile_sorted(v, alpha), quantile_sorted(v, 1 - alpha)};
}

void check_evaluation_input(const std::vector<double>& scores, const std::vector<double>& mos,
                            const std::vector<double>& ci, const EvaluationOptions& options) {
  check_same_length(scores.size(), mos.size(), "evaluation: scores and MOS");
  if (!ci.empty()) check_same_length(ci.size(), mos.size(), "evaluation: MOS and CI");
  if (!(options.confidence > 0 && options.confidence < 1)) {
    throw std::invalid_argument("evaluation: confidence must be in (0, 1)");
  }
  if (options.bootstrap > kMaxBootstrapReplicates) {
    throw std::invalid_argument("evaluation: bootstrap replicates must be at most " +
                                std::to_string(kMaxBootstrapReplicates) + " (got " +
                                std::to_string(options.bootstrap) + ")");
  }
  for (std::size_t i = 0; i < ci.size(); ++i) {
    if (!(ci[i] >= 0) || !std::isfinite(ci[i])) {
      throw NumericError("evaluation: confidence interval " + std::to_string(i + 1) +
                         " is negative or not finite");
    }
  }
}

}  // namespace

double pearson(const std::vector<double>& x, const std::vector<double>& y) {
  check_same_length(x.size(), y.size(), "pearson");
  if (x.size() < 2) return kNaN;
  const double mx = mean_pool(x), my = mean_pool(y);
  double sxx = 0, syy = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
    sxy += (x[i] - mx) * (y[i] - my);
  }
  if (!(sxx > 0 && syy > 0)) return kNaN;
  return std::clamp(sxy / std::sqrt(sxx * syy), -1.0, 1.0);
}

std::vector<double> average_ranks(const std::vector<double>& values) {
  std::vector<std::size_t> order(values.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
  std::vector<double> ranks(values.size());
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i + 1;
    while (j < order.size() && values[order[j]] == values[order[i]]) ++j;
    const double rank = 0.5 * static_cast<double>(i + 1 + j);  // mean of ranks i+1 .. j
    for (std::size_t k = i; k < j; ++k) ranks[order[k]] = rank;
    i = j;
  }
  return ranks;
}

double spearman(const std::vector<double>& x, const std::vector<double>& y) {
  check_same_length(x.size(), y.size(), "spearman");
  return pearson(average_ranks(x), average_ranks(y));
}

double kendall_tau_b(const std::vector<double>& x, const std::vector<double>& y) {
  check_same_length(x.size(), y.size(), "kendall");
  const std::size_t n = x.size();
  if (n < 2) return kNaN;
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return x[a] < x[b] || (x[a] == x[b] && y[a] < y[b]);
  });
  const double pairs = 0.5 * static_cast<double>(n) * static_cast<double>(n - 1);
  const double ties_x =
      tied_pairs(order, [&](std::size_t a, std::size_t b) { return x[a] == x[b]; });
  const double ties_xy =
      tied_pairs(order, [&](std::size_t a, std::size_t b) { return x[a] == x[b] && y[a] == y[b]; });
  const double discordant = sort_counting_inversions(order, y);
  const double ties_y =
      tied_pairs(order, [&](std::size_t a, std::size_t b) { return y[a] == y[b]; });
  const double denominator = std::sqrt((pairs - ties_x) * (pairs - ties_y));
  if (!(denominator > 0)) return kNaN;
  return (pairs - ties_x - ties_y + ties_xy - 2 * discordant) / denominator;
}

double LogisticFunction::operator()(double x) const {
  return beta2 + (beta1 - beta2) * detail::logistic_sigmoid((x - beta3) / std::fabs(beta4));
}

LogisticFit fit_logistic(const std::vector<double>& x, const std::vector<double>& y,
                         const LogisticFitOptions& options) {
  check_fit_input(x, y);
  const Standardised sx = standardise(x, "scores"), sy = standardise(y, "subjective scores");
  return fit_from_starts(sx, sy, default_starts(sx, sy), options);
}

double root_mean_square_error(const std::vector<double>& predicted,
                              const std::vector<double>& observed) {
  check_same_length(predicted.size(), observed.size(), "rmse");
  if (predicted.empty()) return kNaN;
  double sum = 0;
  for (std::size_t i = 0; i < predicted.size(); ++i) {
    sum += (predicted[i] - observed[i]) * (predicted[i] - observed[i]);
  }
  return std::sqrt(sum / static_cast<double>(predicted.size()));
}

double outlier_ratio(const std::vector<double>& predicted, const std::vector<double>& mos,
                     const std::vector<double>& ci95) {
  check_same_length(predicted.size(), mos.size(), "outlier ratio");
  check_same_length(ci95.size(), mos.size(), "outlier ratio");
  if (mos.empty()) return kNaN;
  std::size_t outliers = 0;
  for (std::size_t i = 0; i < mos.size(); ++i) {
    if (std::fabs(predicted[i] - mos[i]) > ci95[i]) ++outliers;
  }
  return static_cast<double>(outliers) / static_cast<double>(mos.size());
}

EvaluationResult evaluate_scores(const std::vector<double>& scores, const std::vector<double>& mos,
                                 const std::vector<double>& mos_ci95,
                                 const EvaluationOptions& options) {
  check_evaluation_input(scores, mos, mos_ci95, options);
  EvaluationResult r;
  r.count = scores.size();
  const bool logistic = options.require_logistic || scores.size() >= kMinPairsForFit;
  if (!logistic && scores.size() < kMinStimuliForCorrelations) {
    throw NumericError("evaluation: " + std::to_string(scores.size()) + " stimuli, at least " +
                       std::to_string(kMinStimuliForCorrelations) + " needed");
  }
  if (logistic) r.fit = fit_logistic(scores, mos, options.fit);
  const Values point =
      logistic ? sample_statistics(scores, mos, mos_ci95, r.fit) : correlations(scores, mos);
  const std::vector<Values> replicates =
      bootstrap_values(scores, mos, mos_ci95, r.fit, options, logistic);
  r.bootstrap_replicates = options.bootstrap;
  r.bootstrap_used = replicates.size();
  std::array<Statistic, kStatisticCount> stats;
  for (std::size_t k = 0; k < kStatisticCount; ++k) {
    const bool defined = logistic || k < kCorrelationCount;
    stats[k] = {point[k],
                defined ? percentile_interval(replicates, k, options.confidence) : std::nullopt};
  }
  r.plcc = stats[0];
  r.srocc = stats[1];
  r.krocc = stats[2];
  r.plcc_logistic = stats[3];
  r.rmse_logistic = stats[4];
  if (!mos_ci95.empty()) r.outlier_ratio = stats[5];
  return r;
}

}  // namespace qm3d::evaluation
