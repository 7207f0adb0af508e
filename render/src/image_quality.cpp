// SSIM and MS-SSIM (qm3d/render/image_quality.h), written from Wang et al. 2004 / 2003 and
// scikit-image 0.19's documented parameters (skimage/metrics/_structural_similarity.py).
#include "qm3d/render/image_quality.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "qm3d/common/large_arrays.h"

namespace qm3d::render {
namespace {

constexpr double kSigma = 1.5;
constexpr double kTruncate = 3.5;  // skimage: truncate = 3.5 with gaussian_weights
constexpr int kRadius = static_cast<int>(kTruncate * kSigma + 0.5);
constexpr double kDataRange = 255;
constexpr double kC1 = (0.01 * kDataRange) * (0.01 * kDataRange);
constexpr double kC2 = (0.03 * kDataRange) * (0.03 * kDataRange);

using Kernel = std::array<double, 2 * kRadius + 1>;

/// scipy.ndimage's _gaussian_kernel1d: exp(-x^2 / (2 sigma^2)) normalised to sum 1.
const Kernel& gaussian_kernel() {
  static const Kernel k = [] {
    Kernel w{};
    double sum = 0;
    for (int i = -kRadius; i <= kRadius; ++i) {
      w[i + kRadius] = std::exp(-0.5 / (kSigma * kSigma) * i * i);
      sum += w[i + kRadius];
    }
    for (double& v : w) v /= sum;
    return w;
  }();
  return k;
}

/// scipy's 'reflect' border (d c b a | a b c d | d c b a).
int reflect(int i, int n) {
  const int period = 2 * n;
  i %= period;
  if (i < 0) i += period;
  return i < n ? i : period - 1 - i;
}

/// A window of an image: [x0, x0 + w) x [y0, y0 + h) (ssim_map uses the whole image).
struct Window {
  int x0 = 0, y0 = 0, w = 0, h = 0;
};

/// The Gaussian filter of `in` (a w x h image), axis 0 then axis 1 as scipy.
std::vector<double> gaussian_filter(const std::vector<double>& in, int w, int h) {
  const Kernel& k = gaussian_kernel();
  std::vector<double> vertical(in.size());
  for (int y = 0; y < h; ++y) {
    double* out = &vertical[static_cast<std::size_t>(y) * w];
    for (int j = -kRadius; j <= kRadius; ++j) {
      const double* row = &in[static_cast<std::size_t>(reflect(y + j, h)) * w];
      const double wj = k[j + kRadius];
      for (int x = 0; x < w; ++x) out[x] += wj * row[x];
    }
  }
  std::vector<double> out(in.size());
  std::vector<double> padded(static_cast<std::size_t>(w) + 2 * kRadius);
  for (int y = 0; y < h; ++y) {
    const double* row = &vertical[static_cast<std::size_t>(y) * w];
    for (int x = -kRadius; x < w + kRadius; ++x) padded[x + kRadius] = row[reflect(x, w)];
    double* o = &out[static_cast<std::size_t>(y) * w];
    for (int x = 0; x < w; ++x) {
      double s = 0;
      for (int j = 0; j <= 2 * kRadius; ++j) s += k[j] * padded[x + j];
      o[x] = s;
    }
  }
  return out;
}

/// Local statistics of a pair over a window (each a filtered image of the window's size).
struct LocalStats {
  std::vector<double> mu_a, mu_b, var_a, var_b, cov;
};

LocalStats local_stats(const GreyImage& a, const GreyImage& b, const Window& win) {
  const std::size_t n = static_cast<std::size_t>(win.w) * win.h;
  std::vector<double> pa(n), pb(n), aa(n), bb(n), ab(n);
  for (int y = 0; y < win.h; ++y) {
    for (int x = 0; x < win.w; ++x) {
      const std::size_t src = static_cast<std::size_t>(win.y0 + y) * a.width + (win.x0 + x);
      const std::size_t dst = static_cast<std::size_t>(y) * win.w + x;
      pa[dst] = a.values[src];
      pb[dst] = b.values[src];
      aa[dst] = pa[dst] * pa[dst];
      bb[dst] = pb[dst] * pb[dst];
      ab[dst] = pa[dst] * pb[dst];
    }
  }
  LocalStats s;
  s.mu_a = gaussian_filter(pa, win.w, win.h);
  s.mu_b = gaussian_filter(pb, win.w, win.h);
  s.var_a = gaussian_filter(aa, win.w, win.h);
  s.var_b = gaussian_filter(bb, win.w, win.h);
  s.cov = gaussian_filter(ab, win.w, win.h);
  for (std::size_t i = 0; i < n; ++i) {
    s.var_a[i] -= s.mu_a[i] * s.mu_a[i];
    s.var_b[i] -= s.mu_b[i] * s.mu_b[i];
    s.cov[i] -= s.mu_a[i] * s.mu_b[i];
  }
  return s;
}

/// skimage: (A1 A2) / (B1 B2).
double ssim_term(const LocalStats& s, std::size_t i) {
  const double a1 = 2 * s.mu_a[i] * s.mu_b[i] + kC1, a2 = 2 * s.cov[i] + kC2;
  const double b1 = s.mu_a[i] * s.mu_a[i] + s.mu_b[i] * s.mu_b[i] + kC1;
  const double b2 = s.var_a[i] + s.var_b[i] + kC2;
  return (a1 * a2) / (b1 * b2);
}

void check_sizes(const GreyImage& a, const GreyImage& b, const std::vector<std::uint8_t>* mask) {
  const std::size_t n = static_cast<std::size_t>(a.width) * a.height;
  if (a.width != b.width || a.height != b.height || a.values.size() != n || b.values.size() != n ||
      (mask && mask->size() != n)) {
    throw std::invalid_argument("SSIM: images (and mask) of different sizes");
  }
}

/// The five Gaussian-filtered quantities at one pixel, in the order of LocalStats.
struct PixelStats {
  double mu_a = 0, mu_b = 0, var_a = 0, var_b = 0, cov = 0;
};

/// Vertically filtered a, b, a^2, b^2, ab of one image row over columns [x_lo, x_hi] (the
/// same sums, in the same order, as gaussian_filter's first pass: the values are identical).
struct RowSums {
  std::vector<double> a, b, aa, bb, ab;
  void fill(const GreyImage& ia, const GreyImage& ib, int y, int x_lo, int x_hi) {
    for (auto* v : {&a, &b, &aa, &bb, &ab}) v->assign(static_cast<std::size_t>(ia.width), 0.0);
    const Kernel& k = gaussian_kernel();
    for (int j = -kRadius; j <= kRadius; ++j) {
      const std::size_t row = static_cast<std::size_t>(reflect(y + j, ia.height)) * ia.width;
      const double wj = k[j + kRadius];
      for (int x = x_lo; x <= x_hi; ++x) {
        const double pa = ia.values[row + x], pb = ib.values[row + x];
        a[x] += wj * pa;
        b[x] += wj * pb;
        aa[x] += wj * (pa * pa);
        bb[x] += wj * (pb * pb);
        ab[x] += wj * (pa * pb);
      }
    }
  }
  /// The second (horizontal) pass at column x, then the moments as local_stats.
  PixelStats at(int x, int width) const {
    const Kernel& k = gaussian_kernel();
    PixelStats s;
    double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
    for (int j = 0; j <= 2 * kRadius; ++j) {
      const int c = reflect(x + j - kRadius, width);
      sa += k[j] * a[c];
      sb += k[j] * b[c];
      saa += k[j] * aa[c];
      sbb += k[j] * bb[c];
      sab += k[j] * ab[c];
    }
    s.mu_a = sa;
    s.mu_b = sb;
    s.var_a = saa - sa * sa;
    s.var_b = sbb - sb * sb;
    s.cov = sab - sa * sb;
    return s;
  }
};

double luminance_term(const PixelStats& s) {
  return (2 * s.mu_a * s.mu_b + kC1) / (s.mu_a * s.mu_a + s.mu_b * s.mu_b + kC1);
}
double contrast_structure_term(const PixelStats& s) {
  return (2 * s.cov + kC2) / (s.var_a + s.var_b + kC2);
}
double ssim_pixel_term(const PixelStats& s) {
  const double a1 = 2 * s.mu_a * s.mu_b + kC1, a2 = 2 * s.cov + kC2;
  const double b1 = s.mu_a * s.mu_a + s.mu_b * s.mu_b + kC1, b2 = s.var_a + s.var_b + kC2;
  return (a1 * a2) / (b1 * b2);
}

/// The mean of term over the mask's pixels (NaN when none). Only the rows holding mask pixels
/// are filtered, each over its mask span grown by the radius, and the second pass runs only at
/// mask pixels: the values are those of the whole-image map, in a fraction of the time.
template <class Term>
double masked_mean(const GreyImage& a, const GreyImage& b, const std::vector<std::uint8_t>& mask,
                   Term term) {
  RowSums sums;
  double sum = 0;
  std::size_t count = 0;
  for (int y = 0; y < a.height; ++y) {
    const std::uint8_t* m = &mask[static_cast<std::size_t>(y) * a.width];
    int first = 0, last = a.width - 1;
    while (first < a.width && !m[first]) ++first;
    if (first == a.width) continue;
    while (!m[last]) --last;
    sums.fill(a, b, y, std::max(0, first - kRadius), std::min(a.width - 1, last + kRadius));
    for (int x = first; x <= last; ++x) {
      if (!m[x]) continue;
      sum += term(sums.at(x, a.width));
      ++count;
    }
  }
  if (count == 0) return std::numeric_limits<double>::quiet_NaN();
  return sum / static_cast<double>(count);
}

GreyImage halve(const GreyImage& in) {
  GreyImage out;
  out.width = in.width / 2;
  out.height = in.height / 2;
  reserve_with_huge_pages(out.values, static_cast<std::size_t>(out.width) * out.height);
  out.values.resize(static_cast<std::size_t>(out.width) * out.height);
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(2 * y) * in.width + 2 * x;
      out.values[static_cast<std::size_t>(y) * out.width + x] =
          (in.values[i] + in.values[i + 1] + in.values[i + in.width] + in.values[i + in.width + 1]) / 4;
    }
  }
  return out;
}

std::vector<std::uint8_t> halve_mask(const std::vector<std::uint8_t>& in, int w, int h) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(w / 2) * (h / 2));
  for (int y = 0; y < h / 2; ++y) {
    for (int x = 0; x < w / 2; ++x) {
      const std::size_t i = static_cast<std::size_t>(2 * y) * w + 2 * x;
      out[static_cast<std::size_t>(y) * (w / 2) + x] = in[i] && in[i + 1] && in[i + w] && in[i + w + 1];
    }
  }
  return out;
}

}  // namespace

std::vector<double> ssim_map(const GreyImage& a, const GreyImage& b) {
  check_sizes(a, b, nullptr);
  const LocalStats s = local_stats(a, b, Window{0, 0, a.width, a.height});
  std::vector<double> out(a.values.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = ssim_term(s, i);
  return out;
}

double masked_ssim(const GreyImage& a, const GreyImage& b, const std::vector<std::uint8_t>& mask) {
  check_sizes(a, b, &mask);
  return masked_mean(a, b, mask, ssim_pixel_term);
}

namespace {

/// MS-SSIM given the mean cs of scale 0 (NaN for an empty mask); the full-scale images are read
/// where they are, each smaller scale made from the previous one.
double ms_ssim_from(const GreyImage& a, const GreyImage& b, const std::vector<std::uint8_t>& mask,
                    double cs0) {
  GreyImage sa, sb;
  std::vector<std::uint8_t> m;
  const GreyImage *pa = &a, *pb = &b;
  const std::vector<std::uint8_t>* pm = &mask;
  double product = 1;
  for (int j = 0; j < kMsSsimScales; ++j) {
    const double cs = j == 0 ? cs0 : masked_mean(*pa, *pb, *pm, contrast_structure_term);
    if (std::isnan(cs)) return cs;
    product *= std::pow(std::max(cs, 0.0), kMsSsimWeights[j]);
    if (j == kMsSsimScales - 1) {
      const double l = masked_mean(*pa, *pb, *pm, luminance_term);
      product *= std::pow(std::max(l, 0.0), kMsSsimWeights[j]);
      break;
    }
    m = halve_mask(*pm, pa->width, pa->height);
    sa = halve(*pa);
    sb = halve(*pb);
    pa = &sa, pb = &sb, pm = &m;
  }
  return product;
}

}  // namespace

double masked_ms_ssim(const GreyImage& a, const GreyImage& b,
                      const std::vector<std::uint8_t>& mask) {
  check_sizes(a, b, &mask);
  return ms_ssim_from(a, b, mask, masked_mean(a, b, mask, contrast_structure_term));
}

SsimScores masked_ssim_scores(const GreyImage& a, const GreyImage& b,
                              const std::vector<std::uint8_t>& mask) {
  check_sizes(a, b, &mask);
  // One pass at full scale gives both S and cs (the same mask pixels, so the same count).
  double cs_sum = 0;
  std::size_t count = 0;
  SsimScores out;
  out.ssim = masked_mean(a, b, mask, [&](const PixelStats& s) {
    cs_sum += contrast_structure_term(s);
    ++count;
    return ssim_pixel_term(s);
  });
  const double cs0 = count ? cs_sum / static_cast<double>(count)
                           : std::numeric_limits<double>::quiet_NaN();
  out.ms_ssim = ms_ssim_from(a, b, mask, cs0);
  return out;
}

}  // namespace qm3d::render
