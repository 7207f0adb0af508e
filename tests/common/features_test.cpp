#include "qm3d/common/features.h"

#include <gtest/gtest.h>

#include <cmath>

namespace qm3d {
namespace {

NeighbourhoodSamples samples(std::vector<double> w1, std::vector<double> w2) {
  NeighbourhoodSamples s;
  const std::size_t n = w1.size();
  s.w1 = std::move(w1);
  s.w2 = std::move(w2);
  s.curv1 = s.curv2 = s.light1 = s.light2 = s.chroma1 = s.chroma2 = s.hue_diff =
      std::vector<double>(n, 0.0);
  return s;
}

TEST(Features, IdenticalNeighbourhoodsGiveExactlyZero) {
  for (const auto& conv : {kCmdmConventions, kPcqmConventions, kMsdm2Conventions}) {
    auto s = samples({1, 1}, {1, 1});
    s.curv1 = s.curv2 = {1, 3};
    s.light1 = s.light2 = {40, 60};
    s.chroma1 = s.chroma2 = {10, 20};
    const FeatureVector f = local_features(s, conv);
    for (std::size_t k = 0; k < kNumFeatures; ++k) EXPECT_EQ(f[k], 0.0) << "f" << k + 1;
  }
}

// curv1 = {0, 2}, curv2 = {1, 5}, unit weights: mu = 1 and 3, sd = 1 and 2, cov = 2.
// f1 = |1 - 3| / (3 + 1) = 0.5; f2 = |1 - 2| / (2 + 1) = 1/3; f3 = |1*2 - 2| / (2 + 1) = 0.
TEST(Features, CurvatureFeaturesByHand) {
  auto s = samples({1, 1}, {1, 1});
  s.curv1 = {0, 2};
  s.curv2 = {1, 5};
  const FeatureVector f = curvature_features(s, kCmdmConventions);
  EXPECT_DOUBLE_EQ(f[0], 0.5);
  EXPECT_DOUBLE_EQ(f[1], 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(f[2], 0.0);
}

// curv1 = {0, 2}, curv2 = {5, 1}: sd 1 and 2, cov = -2.
// CMDM clamps cov to 0: f3 = |2 - 0| / (2 + 1) = 2/3. PCQM keeps -2: |2 + 2| / 3 = 4/3 -> capped at 1.
TEST(Features, CovarianceConventionsDifferAsTheReferencesDo) {
  auto s = samples({1, 1}, {1, 1});
  s.curv1 = {0, 2};
  s.curv2 = {5, 1};
  EXPECT_DOUBLE_EQ(curvature_features(s, kCmdmConventions)[2], 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(curvature_features(s, kPcqmConventions)[2], 1.0);
  // MSDM2: mixed weights (equal here), no clamp, no cap: 4/3.
  EXPECT_DOUBLE_EQ(curvature_features(s, kMsdm2Conventions)[2], 4.0 / 3.0);
}

// L1 = {49, 51}, L2 = {40, 40}: mu 50 vs 40 -> f4 = 1 - 1/(0.002*100 + 1) = 1/6;
// sd 1 vs 0 -> f5 = 1 - 0.1 / (1 + 0.1) = 10/11; cov 0 -> f6 = 1 - 0.1/0.1 = 0.
// C1 = {10, 10}, C2 = {0, 0} -> f7 = 1 - 1/1.2; dH = {3, 3} -> f8 = 1 - 1/(0.008*9 + 1).
TEST(Features, ColorFeaturesByHand) {
  auto s = samples({1, 1}, {1, 1});
  s.light1 = {49, 51};
  s.light2 = {40, 40};
  s.chroma1 = {10, 10};
  s.hue_diff = {3, 3};
  const FeatureVector f = color_features(s, kCmdmConventions);
  EXPECT_NEAR(f[3], 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(f[4], 10.0 / 11.0, 1e-15);
  EXPECT_NEAR(f[5], 0.0, 1e-15);
  EXPECT_NEAR(f[6], 1.0 - 1.0 / 1.2, 1e-15);
  EXPECT_NEAR(f[7], 1.0 - 1.0 / 1.072, 1e-15);
}

// CMDM's sL12 uses w1 while sL2 uses w2, so f6 can be negative (SPEC-CMDM 1.8).
// L1 = L2 = {0, 2}, w1 = {1, 1}, w2 = {3, 1}: sL1 = 1, mu2 = 0.5, sL2 = sqrt(0.75),
// sL12 = ((-1)(-0.5) + (1)(1.5)) / 2 = 1 -> f6 = 1 - 1.1 / (sqrt(0.75) + 0.1) < 0.
TEST(Features, CmdmLightnessStructureCanBeNegative) {
  auto s = samples({1, 1}, {3, 1});
  s.light1 = s.light2 = {0, 2};
  const double f6 = color_features(s, kCmdmConventions)[5];
  EXPECT_NEAR(f6, 1.0 - 1.1 / (std::sqrt(0.75) + 0.1), 1e-15);
  EXPECT_LT(f6, 0.0);
}

// PCQM's lightness structure is unweighted: L1 = L2 = {0, 4} with any weights -> sd 2, cov 4,
// s6 = (4 + 0.1) / (4 + 0.1) = 1, f6 = 0; CMDM with w1 = {1, 3}, w2 = {3, 1} differs.
TEST(Features, PcqmLightnessStructureIgnoresWeights) {
  auto s = samples({1, 3}, {3, 1});
  s.light1 = s.light2 = {0, 4};
  EXPECT_DOUBLE_EQ(color_features(s, kPcqmConventions)[5], 0.0);
  EXPECT_NE(color_features(s, kCmdmConventions)[5], 0.0);
}

TEST(Features, ConstantsAreThePapers) {
  EXPECT_EQ(constants::kLightnessC1, 0.002);
  EXPECT_EQ(constants::kLightnessContrastC2, 0.1);
  EXPECT_EQ(constants::kLightnessStructureC3, 0.1);
  EXPECT_EQ(constants::kChromaC4, 0.002);
  EXPECT_EQ(constants::kHueC5, 0.008);
}

}  // namespace
}  // namespace qm3d
