#include "qm3d/evaluation/training.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "qm3d/common/error.h"

namespace qm3d {
namespace {
using namespace qm3d::evaluation;  // the toolkit under test (qm3d/evaluation/)

double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// Standard normal by Box-Muller (portable, unlike std::normal_distribution).
double normal(std::mt19937_64& rng) {
  const double u1 = 1 - uniform01(rng), u2 = uniform01(rng);
  return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
}

// The true model of the synthetic data: 0.2 f2 + 0.3 f5 + 0.5 f7, MOS = 1 + 4 (1 - sigma).
constexpr FeatureVector kTrueWeights = {0, 0.2, 0, 0, 0.3, 0, 0.5, 0};
const LogisticFunction kTrueMapping{1, 5, 0.5, 0.08};

// `groups` groups of `per_group` stimuli; features uniform in [0, 1) (f3 scaled by 10 to check
// that standardisation makes scales irrelevant); MOS = mapping(true score) + N(0, noise_sd).
TrainingSet synthetic_set(int groups, int per_group, double noise_sd, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  TrainingSet data;
  data.groupings.push_back({"source", {}});
  for (int g = 0; g < groups; ++g) {
    for (int i = 0; i < per_group; ++i) {
      FeatureVector f;
      for (double& v : f) v = uniform01(rng);
      f[2] *= 10;
      double score = 0;
      for (std::size_t k = 0; k < kNumFeatures; ++k) score += kTrueWeights[k] * f[k];
      data.features.push_back(f);
      data.mos.push_back(kTrueMapping(score) + noise_sd * normal(rng));
      data.groupings[0].labels.push_back("g" + std::to_string(g));
    }
  }
  return data;
}

TEST(Subsets, NamesAndParsing) {
  EXPECT_EQ(subset_name(0b01010010), "f2,f5,f7");
  EXPECT_EQ(parse_subset("f2, F5,f7"), 0b01010010u);
  EXPECT_EQ(subset_name(kAllFeatures), "f1,f2,f3,f4,f5,f6,f7,f8");
  EXPECT_THROW(parse_subset(""), FormatError);
  EXPECT_THROW(parse_subset("f2,x"), FormatError);
}

TEST(LinkFit, NoiseFreeDataGiveTheExactWeights) {
  const TrainingSet data = synthetic_set(1, 80, 0.0, 5);
  const LinkFit fit = fit_logistic_link(data.features, data.mos, parse_subset("f2,f5,f7"));
  EXPECT_TRUE(fit.converged);
  for (std::size_t k = 0; k < kNumFeatures; ++k) EXPECT_NEAR(fit.weights[k], kTrueWeights[k], 1e-7);
  EXPECT_NEAR(fit.mos_mapping.beta1, kTrueMapping.beta1, 1e-6);
  EXPECT_NEAR(fit.mos_mapping.beta2, kTrueMapping.beta2, 1e-6);
  EXPECT_NEAR(fit.mos_mapping.beta3, kTrueMapping.beta3, 1e-7);
  EXPECT_NEAR(fit.mos_mapping.beta4, kTrueMapping.beta4, 1e-7);
  EXPECT_LT(fit.rmse, 1e-6);
}

TEST(LinkFit, WeightsGrowWithDistortionAndSumToOne) {
  // The same data with MOS turned into "quality falls as the score rises" upside down: the
  // weights keep sum |w| = 1 and the mapping stays decreasing.
  TrainingSet data = synthetic_set(1, 80, 0.0, 6);
  for (double& m : data.mos) m = 6 - m;
  const LinkFit fit = fit_logistic_link(data.features, data.mos, parse_subset("f2,f5,f7"));
  EXPECT_NEAR(fit.weights[1], -0.2, 1e-7);
  EXPECT_NEAR(fit.weights[6], -0.5, 1e-7);
  EXPECT_LT(fit.mos_mapping.beta1, fit.mos_mapping.beta2);
}

TEST(Training, FindsTheTrueSubsetAndRecoversTheWeights) {
  // 6 groups x 40 stimuli, noise sd 0.1 on a 1..5 MOS scale (seeds 1..8 all pass; the
  // weights come within 0.003 of the truth).
  const TrainingSet data = synthetic_set(6, 40, 0.1, 1);
  const TrainingResult r = train_linear_model(data);
  ASSERT_EQ(r.subsets.size(), 255u);
  EXPECT_EQ(subset_name(r.best), "f2,f5,f7");
  EXPECT_GT(r.subsets.front().plcc_mean, 0.99);
  EXPECT_EQ(r.subsets.front().fold_plcc.size(), 6u);
  // Stated tolerance: each weight within 0.01 of the truth (sum |w| = 1).
  for (std::size_t k = 0; k < kNumFeatures; ++k) {
    EXPECT_NEAR(r.model.weights[k], kTrueWeights[k], 0.01);
  }
  EXPECT_LT(r.model.mos_mapping.beta1, r.model.mos_mapping.beta2);
  EXPECT_EQ(r.folds.size(), 6u);
  EXPECT_EQ(r.folds.front(), "source=g0");
}

TEST(Training, BestSelectionTakesTheTopOfTheRanking) {
  // Without the one-standard-error rule, an irrelevant feature may win by noise (here f1).
  const TrainingSet data = synthetic_set(6, 40, 0.1, 1);
  TrainingOptions o;
  o.subsets = {parse_subset("f2,f5,f7"), parse_subset("f1,f2,f5,f7"), parse_subset("f5,f7")};
  o.selection = SubsetSelection::kBest;
  const TrainingResult best = train_linear_model(data, o);
  EXPECT_EQ(best.best, best.subsets.front().subset);
  EXPECT_GE(best.subsets[0].plcc_mean, best.subsets[1].plcc_mean);
  EXPECT_GE(best.subsets[1].plcc_mean, best.subsets[2].plcc_mean);
  EXPECT_EQ(subset_name(best.subsets.back().subset), "f5,f7");
  o.selection = SubsetSelection::kOneStandardError;
  EXPECT_EQ(subset_name(train_linear_model(data, o).best), "f2,f5,f7");
}

TEST(Training, RefitAndPooledGroupingsAgree) {
  TrainingSet data = synthetic_set(4, 30, 0.05, 2);
  std::vector<std::string> other;  // a second grouping (the report's 5 + 4 folds)
  for (std::size_t i = 0; i < data.mos.size(); ++i) other.push_back(i % 3 ? "a" : "b");
  data.groupings.push_back({"kind", other});
  TrainingOptions o;
  o.subsets = {parse_subset("f2,f5,f7"), parse_subset("f2,f5"), parse_subset("f1")};
  o.final_weights = FinalWeights::kRefit;
  const TrainingResult r = train_linear_model(data, o);
  EXPECT_EQ(r.folds.size(), 6u);
  ASSERT_EQ(r.subsets.size(), 3u);
  EXPECT_EQ(subset_name(r.best), "f2,f5,f7");
  EXPECT_EQ(subset_name(r.subsets.back().subset), "f1");  // uninformative: last
  for (std::size_t k = 0; k < kNumFeatures; ++k)
    EXPECT_NEAR(r.model.weights[k], kTrueWeights[k], 0.02);
}

TEST(Training, ConstantFeatureFailsOnlyItsSubsets) {
  TrainingSet data = synthetic_set(3, 20, 0.05, 3);
  for (FeatureVector& f : data.features) f[7] = 0;  // f8 constant
  TrainingOptions o;
  o.subsets = {parse_subset("f8"), parse_subset("f2,f5,f7")};
  const TrainingResult r = train_linear_model(data, o);
  EXPECT_EQ(subset_name(r.best), "f2,f5,f7");
  EXPECT_EQ(r.subsets.back().error, "feature f8 is constant");
}

TEST(Training, RejectsUnusableGroups) {
  TrainingSet data = synthetic_set(2, 20, 0.05, 4);
  data.groupings[0].labels.assign(data.mos.size(), "one");
  EXPECT_THROW(train_linear_model(data), NumericError);
  data.groupings[0].labels.back() = "tiny";
  try {
    train_linear_model(data);
    FAIL() << "no error";
  } catch (const NumericError& e) {
    EXPECT_EQ(std::string(e.what()),
              "group source=tiny has 1 rows; leave-one-group-out needs at least 3");
  }
}

}  // namespace
}  // namespace qm3d
