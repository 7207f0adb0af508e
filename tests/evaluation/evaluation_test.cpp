#include "qm3d/evaluation/evaluation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>

#include "qm3d/common/error.h"

namespace qm3d {
namespace {
using namespace qm3d::evaluation;  // the toolkit under test (qm3d/evaluation/)

// Portable uniform double in [0, 1) from a standard-specified engine.
double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// O(n^2) Kendall tau-b straight from its definition.
double brute_force_tau_b(const std::vector<double>& x, const std::vector<double>& y) {
  double concordant = 0, discordant = 0, ties_x = 0, ties_y = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    for (std::size_t j = i + 1; j < x.size(); ++j) {
      const double dx = x[i] - x[j], dy = y[i] - y[j];
      if (dx == 0 && dy == 0) continue;
      if (dx == 0)
        ties_x += 1;
      else if (dy == 0)
        ties_y += 1;
      else if ((dx > 0) == (dy > 0))
        concordant += 1;
      else
        discordant += 1;
    }
  }
  return (concordant - discordant) /
         std::sqrt((concordant + discordant + ties_x) * (concordant + discordant + ties_y));
}

TEST(Correlation, PearsonByHand) {
  // dx = -2..2, dy = -2,0,1,0,1: sxy = 6, sxx = 10, syy = 6 -> 6 / sqrt(60).
  EXPECT_NEAR(pearson({1, 2, 3, 4, 5}, {2, 4, 5, 4, 5}), 6 / std::sqrt(60.0), 1e-15);
  EXPECT_DOUBLE_EQ(pearson({1, 2, 3}, {6, 4, 2}), -1.0);
}

TEST(Correlation, UndefinedIsNaN) {
  EXPECT_TRUE(std::isnan(pearson({1, 1, 1}, {1, 2, 3})));
  EXPECT_TRUE(std::isnan(pearson({1}, {2})));
  EXPECT_TRUE(std::isnan(kendall_tau_b({1, 1, 1}, {1, 2, 3})));
  EXPECT_THROW(pearson({1, 2}, {1, 2, 3}), std::invalid_argument);
}

TEST(Correlation, AverageRanksShareTies) {
  EXPECT_EQ(average_ranks({10, 20, 20, 30}), (std::vector<double>{1, 2.5, 2.5, 4}));
  EXPECT_EQ(average_ranks({3, 1, 3, 3}), (std::vector<double>{3, 1, 3, 3}));
}

TEST(Correlation, SpearmanWithTiesByHand) {
  // Ranks x {1, 2.5, 2.5, 4}, y {1, 3, 2, 4}: sxy = 4.5, sxx = 4.5, syy = 5.
  EXPECT_NEAR(spearman({1, 2, 2, 3}, {1, 3, 2, 4}), 4.5 / std::sqrt(22.5), 1e-15);
  // Invariant under a monotone transform of either variable.
  EXPECT_DOUBLE_EQ(spearman({1, 2, 3, 4}, {1, 8, 27, 64}), 1.0);
}

TEST(Correlation, KendallTauBByHand) {
  // 5 concordant pairs, 1 tied in x: 5 / sqrt(5 * 6).
  EXPECT_NEAR(kendall_tau_b({1, 2, 2, 3}, {1, 3, 2, 4}), 5 / std::sqrt(30.0), 1e-15);
  EXPECT_DOUBLE_EQ(kendall_tau_b({1, 2, 3, 4}, {4, 3, 2, 1}), -1.0);
}

TEST(Correlation, KendallMatchesTheDefinitionWithManyTies) {
  std::mt19937_64 rng(7);
  std::vector<double> x, y;
  for (int i = 0; i < 300; ++i) {
    x.push_back(std::floor(uniform01(rng) * 12));  // many ties
    y.push_back(std::floor(x.back() / 2 + uniform01(rng) * 8));
  }
  EXPECT_NEAR(kendall_tau_b(x, y), brute_force_tau_b(x, y), 1e-12);
}

TEST(Logistic, FunctionIsMonotoneBetweenItsAsymptotes) {
  const LogisticFunction f{1, 5, 0.4, -0.1};  // only |beta4| counts
  EXPECT_NEAR(f(0.4), 3.0, 1e-15);
  EXPECT_NEAR(f(100), 1.0, 1e-12);
  EXPECT_NEAR(f(-100), 5.0, 1e-12);
  for (double x = -1; x < 1; x += 0.01) EXPECT_LE(f(x + 0.01), f(x));
}

TEST(Logistic, RecoversExactParameters) {
  const LogisticFunction truth{1.2, 4.8, 0.03, 0.007};  // decreasing, PCQM-like scale
  std::vector<double> x, y;
  for (int i = 0; i < 60; ++i) {
    x.push_back(0.001 * i);
    y.push_back(truth(x.back()));
  }
  const LogisticFit fit = fit_logistic(x, y);
  EXPECT_TRUE(fit.converged);
  EXPECT_NEAR(fit.function.beta1, truth.beta1, 1e-6);
  EXPECT_NEAR(fit.function.beta2, truth.beta2, 1e-6);
  EXPECT_NEAR(fit.function.beta3, truth.beta3, 1e-8);
  EXPECT_NEAR(std::fabs(fit.function.beta4), truth.beta4, 1e-8);
  EXPECT_LT(fit.rmse, 1e-7);
}

TEST(Logistic, ImprovesOnALinearFitOfACurvedResponse) {
  std::mt19937_64 rng(3);
  std::vector<double> x, y;
  for (int i = 0; i < 200; ++i) {
    x.push_back(uniform01(rng));
    y.push_back(1 + 4 / (1 + std::exp((x.back() - 0.5) / 0.05)) + 0.1 * (uniform01(rng) - 0.5));
  }
  const LogisticFit fit = fit_logistic(x, y);
  std::vector<double> mapped;
  for (double v : x) mapped.push_back(fit.function(v));
  EXPECT_GT(pearson(mapped, y), std::fabs(pearson(x, y)) + 0.02);
  EXPECT_GT(pearson(mapped, y), 0.99);
}

TEST(Logistic, RejectsDegenerateInput) {
  EXPECT_THROW(fit_logistic({1, 2, 3}, {1, 2, 3}), NumericError);
  EXPECT_THROW(fit_logistic({1, 1, 1, 1, 1}, {1, 2, 3, 4, 5}), NumericError);
  EXPECT_THROW(fit_logistic({1, 2, 3, 4, NAN}, {1, 2, 3, 4, 5}), NumericError);
}

TEST(Outliers, ErrorBeyondTheConfidenceInterval) {
  // Errors 0.1, 0.5, 0.3, 0 against half-widths 0.2, 0.4, 0.3, 0.1: only the second is out
  // (the third equals its bound).
  EXPECT_DOUBLE_EQ(outlier_ratio({1.1, 2.5, 2.7, 4}, {1, 2, 3, 4}, {0.2, 0.4, 0.3, 0.1}), 0.25);
  EXPECT_DOUBLE_EQ(root_mean_square_error({1, 2}, {2, 4}), std::sqrt(2.5));
}

std::vector<double> noisy_scores(std::vector<double>& mos, int n) {
  std::mt19937_64 rng(11);
  std::vector<double> scores;
  for (int i = 0; i < n; ++i) {
    scores.push_back(uniform01(rng));
    mos.push_back(5 - 4 * scores.back() * scores.back() + 0.6 * (uniform01(rng) - 0.5));
  }
  return scores;
}

TEST(Evaluation, PointValuesAndDeterministicIntervals) {
  std::vector<double> mos;
  const std::vector<double> scores = noisy_scores(mos, 120);
  EvaluationOptions o;
  o.bootstrap = 200;
  const EvaluationResult a = evaluate_scores(scores, mos, {}, o);
  EXPECT_EQ(a.count, 120u);
  EXPECT_DOUBLE_EQ(a.plcc.value, pearson(scores, mos));
  EXPECT_DOUBLE_EQ(a.srocc.value, spearman(scores, mos));
  EXPECT_DOUBLE_EQ(a.krocc.value, kendall_tau_b(scores, mos));
  EXPECT_GT(a.plcc_logistic.value, std::fabs(a.plcc.value));
  EXPECT_FALSE(a.outlier_ratio.has_value());
  EXPECT_EQ(a.bootstrap_used, 200u);
  ASSERT_TRUE(a.srocc.ci.has_value());
  EXPECT_LT(a.srocc.ci->low, a.srocc.value);
  EXPECT_GT(a.srocc.ci->high, a.srocc.value);
  const EvaluationResult b = evaluate_scores(scores, mos, {}, o);
  EXPECT_EQ(a.plcc_logistic.ci->low, b.plcc_logistic.ci->low);
  EXPECT_EQ(a.rmse_logistic.ci->high, b.rmse_logistic.ci->high);
  o.seed = 2;
  EXPECT_NE(evaluate_scores(scores, mos, {}, o).srocc.ci->low, a.srocc.ci->low);
}

// A count read from a negative number wraps round to ~1.8e19 and would never end (issue 24).
TEST(Evaluation, BootstrapCountIsBounded) {
  std::vector<double> mos;
  const std::vector<double> scores = noisy_scores(mos, 20);
  EvaluationOptions o;
  o.bootstrap = static_cast<std::size_t>(-1);
  EXPECT_THROW(evaluate_scores(scores, mos, {}, o), std::invalid_argument);
  o.bootstrap = std::size_t(1) << 40;
  EXPECT_THROW(evaluate_scores(scores, mos, {}, o), std::invalid_argument);
  o.bootstrap = kMaxBootstrapReplicates + 1;
  EXPECT_THROW(evaluate_scores(scores, mos, {}, o), std::invalid_argument);
}

TEST(Evaluation, OutlierRatioOnlyWithIntervals) {
  std::vector<double> mos;
  const std::vector<double> scores = noisy_scores(mos, 40);
  EvaluationOptions o;
  o.bootstrap = 0;
  const EvaluationResult r = evaluate_scores(scores, mos, std::vector<double>(40, 0.2), o);
  ASSERT_TRUE(r.outlier_ratio.has_value());
  EXPECT_GT(r.outlier_ratio->value, 0.0);
  EXPECT_LT(r.outlier_ratio->value, 1.0);
  EXPECT_FALSE(r.plcc.ci.has_value());
  EXPECT_THROW(evaluate_scores(scores, mos, std::vector<double>(40, -1.0), o), NumericError);
  EXPECT_THROW(evaluate_scores(std::vector<double>(40, 1.0), mos, {}, o), NumericError);
}

}  // namespace
}  // namespace qm3d
