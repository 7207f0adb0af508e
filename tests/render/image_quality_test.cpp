// SSIM / MS-SSIM (qm3d/render/image_quality.h) against a direct re-derivation in this file:
// a 2-D 11x11 Gaussian window summed pixel by pixel with scipy's 'reflect' borders (no
// separable filter, no cropping), and MS-SSIM written from Wang et al. 2003 eq. 7 with the
// pooling the header documents.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <vector>

#include "qm3d/render/image_quality.h"

namespace qm3d::render {
namespace {

constexpr double kC1 = 6.5025;   // (0.01 * 255)^2
constexpr double kC2 = 58.5225;  // (0.03 * 255)^2

GreyImage random_image(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 255);
  GreyImage g{w, h, std::vector<double>(static_cast<std::size_t>(w) * h)};
  for (double& v : g.values) v = u(rng);
  return g;
}

GreyImage noisy_copy(const GreyImage& in, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  GreyImage g = in;
  for (double& v : g.values) v = std::clamp(v + u(rng), 0.0, 255.0);
  return g;
}

int reflect_index(int i, int n) {
  while (i < 0 || i >= n) i = i < 0 ? -i - 1 : 2 * n - i - 1;
  return i;
}

/// The five local statistics at (x, y) from the full 2-D window.
struct Stats {
  double ma = 0, mb = 0, vaa = 0, vbb = 0, vab = 0;
};

Stats direct_stats(const GreyImage& a, const GreyImage& b, int x, int y) {
  double w1[11], sum = 0;
  for (int i = 0; i < 11; ++i) sum += w1[i] = std::exp(-(i - 5) * (i - 5) / (2 * 1.5 * 1.5));
  Stats s;
  for (int j = 0; j < 11; ++j) {
    for (int i = 0; i < 11; ++i) {
      const double w = w1[i] / sum * w1[j] / sum;
      const std::size_t k = static_cast<std::size_t>(reflect_index(y + j - 5, a.height)) * a.width +
                            reflect_index(x + i - 5, a.width);
      const double pa = a.values[k], pb = b.values[k];
      s.ma += w * pa;
      s.mb += w * pb;
      s.vaa += w * pa * pa;
      s.vbb += w * pb * pb;
      s.vab += w * pa * pb;
    }
  }
  s.vaa -= s.ma * s.ma;
  s.vbb -= s.mb * s.mb;
  s.vab -= s.ma * s.mb;
  return s;
}

double l_term(const Stats& s) { return (2 * s.ma * s.mb + kC1) / (s.ma * s.ma + s.mb * s.mb + kC1); }
double cs_term(const Stats& s) { return (2 * s.vab + kC2) / (s.vaa + s.vbb + kC2); }

/// Mean of term over the mask (all pixels when the mask is empty of size).
template <class Term>
double direct_mean(const GreyImage& a, const GreyImage& b, const std::vector<std::uint8_t>& mask,
                   Term term) {
  double sum = 0;
  int n = 0;
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      if (!mask[static_cast<std::size_t>(y) * a.width + x]) continue;
      sum += term(direct_stats(a, b, x, y));
      ++n;
    }
  }
  return sum / n;
}

double direct_ssim(const GreyImage& a, const GreyImage& b, const std::vector<std::uint8_t>& m) {
  return direct_mean(a, b, m, [](const Stats& s) { return l_term(s) * cs_term(s); });
}

/// Wang et al. 2003 eq. 7 with 2x2 block-mean downsampling and an all-four-pixels mask rule.
double direct_ms_ssim(GreyImage a, GreyImage b, std::vector<std::uint8_t> m) {
  const double beta[5] = {0.0448, 0.2856, 0.3001, 0.2363, 0.1333};
  double result = 1;
  for (int j = 0; j < 5; ++j) {
    result *= std::pow(std::max(0.0, direct_mean(a, b, m, cs_term)), beta[j]);
    if (j == 4) return result * std::pow(direct_mean(a, b, m, l_term), beta[4]);
    const int w = a.width / 2, h = a.height / 2;
    GreyImage a2{w, h, {}}, b2{w, h, {}};
    std::vector<std::uint8_t> m2;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const auto at = [&](int dx, int dy) {
          return static_cast<std::size_t>(2 * y + dy) * a.width + 2 * x + dx;
        };
        a2.values.push_back((a.values[at(0, 0)] + a.values[at(1, 0)] + a.values[at(0, 1)] +
                             a.values[at(1, 1)]) / 4);
        b2.values.push_back((b.values[at(0, 0)] + b.values[at(1, 0)] + b.values[at(0, 1)] +
                             b.values[at(1, 1)]) / 4);
        m2.push_back(m[at(0, 0)] && m[at(1, 0)] && m[at(0, 1)] && m[at(1, 1)]);
      }
    }
    a = a2;
    b = b2;
    m = m2;
  }
  return result;
}

std::vector<std::uint8_t> full_mask(const GreyImage& g) {
  return std::vector<std::uint8_t>(g.values.size(), 1);
}

/// A disc-shaped mask of radius r centred in the image.
std::vector<std::uint8_t> disc_mask(const GreyImage& g, double r) {
  std::vector<std::uint8_t> m(g.values.size());
  for (int y = 0; y < g.height; ++y) {
    for (int x = 0; x < g.width; ++x) {
      const double dx = x - g.width / 2.0, dy = y - g.height / 2.0;
      m[static_cast<std::size_t>(y) * g.width + x] = dx * dx + dy * dy < r * r;
    }
  }
  return m;
}

TEST(Ssim, IdenticalImagesGiveOne) {
  const GreyImage a = random_image(37, 29, 1);
  EXPECT_NEAR(masked_ssim(a, a, full_mask(a)), 1.0, 1e-12);
  EXPECT_NEAR(masked_ms_ssim(a, a, full_mask(a)), 1.0, 1e-12);
  for (double s : ssim_map(a, a)) ASSERT_NEAR(s, 1.0, 1e-12);
}

TEST(Ssim, ConstantImagesByFormula) {
  // Two constant images 100 and 150: variances 0, so S = (2*100*150 + C1) / (100^2 + 150^2 + C1).
  const GreyImage a{16, 12, std::vector<double>(16 * 12, 100.0)};
  const GreyImage b{16, 12, std::vector<double>(16 * 12, 150.0)};
  const double expected = (2 * 100.0 * 150 + kC1) / (100.0 * 100 + 150.0 * 150 + kC1);
  EXPECT_NEAR(masked_ssim(a, b, full_mask(a)), expected, 1e-12);
  for (double s : ssim_map(a, b)) ASSERT_NEAR(s, expected, 1e-12);
}

TEST(Ssim, MapEqualsDirectWindowEverywhere) {
  const GreyImage a = random_image(23, 19, 2), b = noisy_copy(a, 40, 3);
  const std::vector<double> map = ssim_map(a, b);
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      const Stats s = direct_stats(a, b, x, y);
      ASSERT_NEAR(map[static_cast<std::size_t>(y) * a.width + x], l_term(s) * cs_term(s), 1e-12)
          << x << "," << y;
    }
  }
}

TEST(Ssim, MaskedMeanEqualsDirectAndFullMap) {
  const GreyImage a = random_image(41, 33, 4), b = noisy_copy(a, 30, 5);
  const std::vector<std::uint8_t> m = disc_mask(a, 12);
  EXPECT_NEAR(masked_ssim(a, b, m), direct_ssim(a, b, m), 1e-12);
  // The masked mean is that of the whole-image map over the mask (computed in a window only).
  const std::vector<double> map = ssim_map(a, b);
  double sum = 0;
  int n = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    if (m[i]) sum += map[i], ++n;
  }
  EXPECT_NEAR(masked_ssim(a, b, m), sum / n, 1e-12);
  // A pixel farther than the window radius (5) from every mask pixel does not count; one just
  // outside the mask does (the window reads it): the mask selects pixels, it does not crop.
  GreyImage far = b, near = b;
  far.values[0] = 255 - far.values[0];  // corner: > 20 px from the disc
  const std::size_t edge = static_cast<std::size_t>(16) * a.width + 20 + 13;  // 1 px outside
  near.values[edge] = 255 - near.values[edge];
  EXPECT_DOUBLE_EQ(masked_ssim(a, far, m), masked_ssim(a, b, m));
  EXPECT_NE(masked_ssim(a, near, m), masked_ssim(a, b, m));
}

TEST(Ssim, Symmetric) {
  const GreyImage a = random_image(30, 30, 6), b = noisy_copy(a, 60, 7);
  const std::vector<std::uint8_t> m = disc_mask(a, 10);
  EXPECT_NEAR(masked_ssim(a, b, m), masked_ssim(b, a, m), 1e-14);
  EXPECT_NEAR(masked_ms_ssim(a, b, full_mask(a)), masked_ms_ssim(b, a, full_mask(a)), 1e-14);
}

TEST(Ssim, NoiseLowersTheScore) {
  const GreyImage a = random_image(32, 32, 8);
  const double mild = masked_ssim(a, noisy_copy(a, 10, 9), full_mask(a));
  const double strong = masked_ssim(a, noisy_copy(a, 80, 9), full_mask(a));
  EXPECT_LT(strong, mild);
  EXPECT_LT(mild, 1.0);
}

TEST(Ssim, InvalidSizesRejected) {
  const GreyImage a = random_image(10, 10, 10), b = random_image(10, 11, 11);
  EXPECT_THROW(ssim_map(a, b), std::invalid_argument);
  EXPECT_THROW(masked_ssim(a, b, full_mask(a)), std::invalid_argument);
  EXPECT_THROW(masked_ms_ssim(a, b, full_mask(a)), std::invalid_argument);
  EXPECT_THROW(masked_ssim(a, a, std::vector<std::uint8_t>(99, 1)), std::invalid_argument);
  GreyImage short_values = a;
  short_values.values.pop_back();
  EXPECT_THROW(masked_ssim(a, short_values, full_mask(a)), std::invalid_argument);
}

TEST(Ssim, EmptyMaskIsNaN) {
  const GreyImage a = random_image(12, 12, 12);
  const std::vector<std::uint8_t> none(a.values.size(), 0);
  EXPECT_TRUE(std::isnan(masked_ssim(a, a, none)));
  EXPECT_TRUE(std::isnan(masked_ms_ssim(a, a, none)));
}

TEST(MsSsim, EqualsPaperFormulaFullMask) {
  const GreyImage a = random_image(67, 53, 13), b = noisy_copy(a, 35, 14);
  EXPECT_NEAR(masked_ms_ssim(a, b, full_mask(a)), direct_ms_ssim(a, b, full_mask(a)), 1e-12);
}

TEST(MsSsim, EqualsPaperFormulaDiscMask) {
  const GreyImage a = random_image(96, 80, 15), b = noisy_copy(a, 25, 16);
  const std::vector<std::uint8_t> m = disc_mask(a, 36);
  const double ours = masked_ms_ssim(a, b, m);
  EXPECT_NEAR(ours, direct_ms_ssim(a, b, m), 1e-12);
  EXPECT_GT(ours, 0.0);
  EXPECT_LT(ours, 1.0);
}

TEST(MsSsim, CombinedScoresEqualSeparateCalls) {
  const GreyImage a = random_image(70, 64, 17), b = noisy_copy(a, 30, 18);
  const std::vector<std::uint8_t> m = disc_mask(a, 28);
  const SsimScores both = masked_ssim_scores(a, b, m);
  EXPECT_EQ(both.ssim, masked_ssim(a, b, m));
  EXPECT_EQ(both.ms_ssim, masked_ms_ssim(a, b, m));
  const std::vector<std::uint8_t> none(m.size(), 0);
  EXPECT_TRUE(std::isnan(masked_ssim_scores(a, b, none).ssim));
  EXPECT_TRUE(std::isnan(masked_ssim_scores(a, b, none).ms_ssim));
  EXPECT_THROW(masked_ssim_scores(a, random_image(70, 63, 1), m), std::invalid_argument);
}

TEST(MsSsim, WeightsArePapers) {
  // Wang et al. 2003, section 3.2 (they sum to 1.0001, as printed in the paper).
  const double paper[5] = {0.0448, 0.2856, 0.3001, 0.2363, 0.1333};
  for (int j = 0; j < kMsSsimScales; ++j) EXPECT_EQ(kMsSsimWeights[j], paper[j]);
}

}  // namespace
}  // namespace qm3d::render
