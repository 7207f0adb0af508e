// BatchFft (render/src/icid_fft.h), the FFT of iCID's CSF filtering: forward transforms against
// a direct DFT in long double, inverse(forward(x)) = x, the centre-third inverse equal to the
// full one there, and every lane independent of the others; the CSF filtering's pruned
// transforms (render/src/icid_csf.h) against the full 3n-point ones.
#include "icid_fft.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <random>
#include <utility>
#include <vector>

#include "icid_csf.h"

namespace qm3d::render::icid_detail {
namespace {

constexpr int kLanes = BatchFft::kLanes;

struct Block {
  std::vector<double> re, im;
  explicit Block(int n) : re(static_cast<std::size_t>(n) * kLanes), im(re.size()) {}
};

Block random_block(int n, unsigned seed) {
  Block b(n);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  for (std::size_t e = 0; e < b.re.size(); ++e) {
    b.re[e] = u(rng);
    b.im[e] = u(rng);
  }
  return b;
}

/// w^m = exp(-2 pi i m / n), m = 0 .. n - 1, in long double.
std::vector<std::complex<long double>> roots(int n) {
  const long double pi = 3.141592653589793238462643383279502884L;
  std::vector<std::complex<long double>> w(n);
  for (int m = 0; m < n; ++m) w[m] = std::polar(1.0L, -2 * pi * m / n);
  return w;
}

/// X_k of lane c by the definition, in long double.
std::complex<long double> direct_dft(const Block& x,
                                     const std::vector<std::complex<long double>>& w, int c,
                                     int k) {
  const int n = static_cast<int>(w.size());
  std::complex<long double> sum = 0;
  for (int j = 0; j < n; ++j) {
    sum += std::complex<long double>(x.re[j * kLanes + c], x.im[j * kLanes + c]) *
           w[(1LL * j * k) % n];
  }
  return sum;
}

/// x transformed in place (BatchFft leaves the result in either pair of buffers).
void transform(const BatchFft& fft, Block& x, Block& work, bool inverse, bool centre = false) {
  BatchFft::Buffers io{x.re.data(), x.im.data(), work.re.data(), work.im.data()};
  if (inverse) {
    fft.inverse(io, centre);
  } else {
    fft.forward(io);
  }
  if (io.re != x.re.data()) {
    x.re.swap(work.re);
    x.im.swap(work.im);
  }
}

const int kLengths[] = {1, 2, 3, 4, 5, 6, 8, 12, 30, 49, 96, 143, 429, 504, 768};

TEST(IcidFft, ForwardIsTheDft) {
  for (int n : kLengths) {
    ASSERT_TRUE(BatchFft::supported(n)) << n;
    const BatchFft fft(n);
    const Block x = random_block(n, n);
    Block y = x, work(n);
    transform(fft, y, work, false);
    const auto w = roots(n);
    for (int c = 0; c < kLanes; ++c) {
      for (int k = 0; k < n; ++k) {
        const auto want = direct_dft(x, w, c, k);
        const double tolerance = 1e-14 * n;
        EXPECT_NEAR(y.re[k * kLanes + c], static_cast<double>(want.real()), tolerance) << n;
        EXPECT_NEAR(y.im[k * kLanes + c], static_cast<double>(want.imag()), tolerance) << n;
      }
    }
  }
}

TEST(IcidFft, InverseUndoesForwardAndCentreThirdIsExact) {
  for (int n : kLengths) {
    const BatchFft fft(n);
    const Block x = random_block(n, 1000 + n);
    Block y = x, work(n);
    transform(fft, y, work, false);
    Block centre = y;
    transform(fft, y, work, true);
    for (std::size_t e = 0; e < x.re.size(); ++e) {
      EXPECT_NEAR(y.re[e], x.re[e], 1e-14 * n) << n;
      EXPECT_NEAR(y.im[e], x.im[e], 1e-14 * n) << n;
    }
    if (n % 3 != 0) continue;
    transform(fft, centre, work, true, true);
    for (std::size_t e = static_cast<std::size_t>(n / 3) * kLanes; e < 2u * (n / 3) * kLanes; ++e) {
      EXPECT_EQ(centre.re[e], y.re[e]) << n;
      EXPECT_EQ(centre.im[e], y.im[e]) << n;
    }
  }
}

TEST(IcidFft, LanesAreIndependent) {
  const int n = 768;
  const BatchFft fft(n);
  Block a = random_block(n, 7), b = a, work(n);
  for (std::size_t e = 0; e < b.re.size(); e += kLanes) b.re[e + 3] = b.im[e + 3] = 0.5;
  transform(fft, a, work, false);
  transform(fft, b, work, false);
  for (std::size_t e = 0; e < a.re.size(); ++e) {
    if (e % kLanes == 3) continue;
    EXPECT_EQ(a.re[e], b.re[e]);
    EXPECT_EQ(a.im[e], b.im[e]);
  }
  EXPECT_FALSE(BatchFft::supported(17 * 3));
  EXPECT_FALSE(BatchFft::supported(0));
}

XyzPlanes random_planes(int rows, int cols, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  XyzPlanes p{rows, cols, {}, {}, {}};
  for (auto* plane : {&p.x, &p.y, &p.z}) {
    plane->resize(static_cast<std::size_t>(rows) * cols);
    for (double& v : *plane) v = u(rng);
  }
  return p;
}

// The pruned transforms (the lines k, l = 2 mod 3 left out, n-point FFTs) give the filtering
// of the full 3n-point ones to rounding: sides that are multiples of 4 (the 4 x 4 tiles), other
// sides and partial lane blocks (the scalar loops), on one and two threads.
TEST(IcidFft, PrunedCsfEqualsFullTransforms) {
  const int sizes[][2] = {{64, 40}, {16, 15}, {26, 30}, {45, 98}, {126, 150}};
  for (const auto& size : sizes) {
    for (const int threads : {1, 2}) {
      XyzPlanes a = random_planes(size[0], size[1], 3), b = random_planes(size[0], size[1], 4);
      XyzPlanes fa = a, fb = b;
      csf_filter(a, b, threads);
      csf_filter_full_transforms(fa, fb, threads);
      double worst = 0;
      for (const auto& [got, want] : {std::pair{&a.x, &fa.x},
                                      {&a.y, &fa.y},
                                      {&a.z, &fa.z},
                                      {&b.x, &fb.x},
                                      {&b.y, &fb.y},
                                      {&b.z, &fb.z}}) {
        for (std::size_t i = 0; i < got->size(); ++i)
          worst = std::max(worst, std::abs((*got)[i] - (*want)[i]));
      }
      EXPECT_LT(worst, 1e-13) << size[0] << "x" << size[1] << ", " << threads << " threads";
      EXPECT_GT(std::abs(a.y[0] - random_planes(size[0], size[1], 3).y[0]), 1e-6);  // filtered
    }
  }
}

}  // namespace
}  // namespace qm3d::render::icid_detail
