#include "qm3d/common/pooling.h"

#include <gtest/gtest.h>

#include <cmath>

namespace qm3d {
namespace {

TEST(Pooling, MeanAndMinkowski) {
  EXPECT_DOUBLE_EQ(mean_pool({1, 2, 6}), 3.0);
  EXPECT_DOUBLE_EQ(mean_pool({}), 0.0);
  // (1^3 + 2^3) / 2 = 4.5 -> 4.5^(1/3)
  EXPECT_DOUBLE_EQ(minkowski_pool({1, 2}, 3), std::cbrt(4.5));
  EXPECT_DOUBLE_EQ(minkowski_pool({0.5, 0.5}, 3), 0.5);
}

TEST(Pooling, MeanFeaturesIsComponentWise) {
  FeatureVector a{}, b{};
  a[1] = 1;
  b[1] = 3;
  b[7] = 4;
  const FeatureVector m = mean_features({a, b});
  EXPECT_DOUBLE_EQ(m[1], 2.0);
  EXPECT_DOUBLE_EQ(m[7], 2.0);
  EXPECT_DOUBLE_EQ(m[0], 0.0);
}

TEST(Pooling, BuiltInModelsHoldThePublishedWeights) {
  FeatureVector f{1, 2, 3, 4, 5, 6, 7, 8};
  EXPECT_NEAR(cmdm_model().apply(f), 0.091 * 2 + 0.22 * 5 + 0.032 * 6 + 0.656 * 7, 1e-15);
  EXPECT_NEAR(pcqm_model().apply(f), 0.0057 * 3 + 0.9771 * 4 + 0.0172 * 6, 1e-15);
  double sum = 0;
  for (double w : pcqm_model().weights) sum += w;
  EXPECT_NEAR(sum, 1.0, 1e-15);  // PCQM's weights sum to 1
}

}  // namespace
}  // namespace qm3d
