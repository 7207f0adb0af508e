#include "qm3d/common/statistics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace qm3d {
namespace {

TEST(Statistics, GaussianWeightUsesTheReferencesConstant) {
  const double sigma = 0.5;
  EXPECT_DOUBLE_EQ(gaussian_weight(0, sigma), 1.0 / sigma / std::sqrt(2 * 3.141592));
  EXPECT_NEAR(gaussian_weight(sigma, sigma) / gaussian_weight(0, sigma), std::exp(-0.5), 1e-15);
}

// The vectorised weights: within 4 ulp of the scalar expression (libmvec's bound; exactly it
// without libmvec), and each element's weight independent of where it stands in the array and of
// the array's length (the walk tests compare samples gathered in different orders bit for bit).
TEST(Statistics, GaussianWeightsInPlaceMatchTheScalarWeights) {
  const double sigma = 0.0123;
  std::vector<double> d;
  for (int i = 0; i < 103; ++i) d.push_back(0.0007 * i * (i % 3 == 0 ? 1.0 : 0.37));
  d.push_back(0.0);
  d.push_back(1e-300);
  d.push_back(10.0);  // underflows to 0
  std::vector<double> w = d;
  gaussian_weights_in_place(w.data(), w.size(), sigma);
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double scalar = gaussian_weight(d[i], sigma);
    EXPECT_NEAR(w[i], scalar, 4 * std::numeric_limits<double>::epsilon() * scalar) << d[i];
    for (std::size_t n : {std::size_t{1}, std::size_t{3}, std::size_t{6}}) {  // other lanes, tails
      std::vector<double> alone(n, 0.5 * sigma);
      alone[n - 1] = d[i];
      gaussian_weights_in_place(alone.data(), n, sigma);
      EXPECT_EQ(alone[n - 1], w[i]) << "distance " << d[i] << " at position " << n - 1;
    }
  }
  gaussian_weights_in_place(nullptr, 0, sigma);  // nothing to do
}

// x1 = {0, 2}, x2 = {1, 5}, w1 = {1, 1}, w2 = {1, 3}:
// mean1 = 1, var1 = (1 + 1) / 2 = 1; mean2 = (1 + 15) / 4 = 4, var2 = (1*9 + 3*1) / 4 = 3;
// d1 = {-1, 1}, d2 = {-3, 1}: first-weight cov = (3 + 1) / 2 = 2, mixed cov = (1*3 + 3*1) / 2 = 3.
TEST(Statistics, WeightedMomentsByHand) {
  const std::vector<double> x1{0, 2}, x2{1, 5}, w1{1, 1}, w2{1, 3};
  const auto first = weighted_moments(x1, x2, w1, w2, {CovarianceWeighting::kFirst, false});
  EXPECT_DOUBLE_EQ(first.mean1, 1);
  EXPECT_DOUBLE_EQ(first.mean2, 4);
  EXPECT_DOUBLE_EQ(first.sd1, 1);
  EXPECT_DOUBLE_EQ(first.sd2, std::sqrt(3.0));
  EXPECT_DOUBLE_EQ(first.cov12, 2);
  const auto mixed = weighted_moments(x1, x2, w1, w2, {CovarianceWeighting::kMixed, false});
  EXPECT_DOUBLE_EQ(mixed.cov12, 3);
}

// x1 = {0, 2}, x2 = {5, 1}, unit weights: d1 = {-1, 1}, d2 = {2, -2}, cov = -2.
TEST(Statistics, CovarianceClampIsOptional) {
  const std::vector<double> x1{0, 2}, x2{5, 1}, w{1, 1};
  EXPECT_DOUBLE_EQ(weighted_moments(x1, x2, w, w, {CovarianceWeighting::kFirst, false}).cov12, -2);
  EXPECT_DOUBLE_EQ(weighted_moments(x1, x2, w, w, {CovarianceWeighting::kFirst, true}).cov12, 0);
}

// x1 = {0, 4}, x2 = {2, 2}: means 2 and 2, sd 2 and 0, cov 0 (divide by n).
TEST(Statistics, UnweightedMomentsByHand) {
  const auto m = unweighted_moments({0, 4}, {2, 2});
  EXPECT_DOUBLE_EQ(m.mean1, 2);
  EXPECT_DOUBLE_EQ(m.mean2, 2);
  EXPECT_DOUBLE_EQ(m.sd1, 2);
  EXPECT_DOUBLE_EQ(m.sd2, 0);
  EXPECT_DOUBLE_EQ(m.cov12, 0);
}

TEST(Statistics, WeightedMean) { EXPECT_DOUBLE_EQ(weighted_mean({1, 5}, {3, 1}), 2.0); }

}  // namespace
}  // namespace qm3d
