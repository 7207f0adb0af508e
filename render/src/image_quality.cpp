// SSIM and MS-SSIM (qm3d/render/image_quality.h), written from Wang et al. 2004 / 2003 and
// scikit-image 0.19's documented parameters (skimage/metrics/_structural_similarity.py).
#include "qm3d/render/image_quality.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "qm3d/common/cpu.h"
#include "ssim_stream.h"

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

/// Rows a scale keeps: a row is scored once the kRadius rows below it have come (or the last
/// row has), so the rows it reads (reflected at the borders: within kRadius of it) are at most
/// 3 kRadius + 1 = 16 rows old.
constexpr int kRingRows = 16;
static_assert(kRingRows >= 3 * kRadius + 1, "the ring holds every row a window reads");

double mean_or_nan(double sum, std::size_t count) {
  return count ? sum / static_cast<double>(count) : std::numeric_limits<double>::quiet_NaN();
}

/// Two doubles per instruction (SSE2 on every x86-64; a compiler splits them elsewhere), or four
/// (AVX2, where the processor has it): each lane is IEEE arithmetic on its own column (no fused
/// multiply-add: AVX2 does not bring FMA), the scalar expression's value bit for bit, so the
/// values do not depend on the processor.
using Lanes = double __attribute__((vector_size(16)));
using Lanes4 = double __attribute__((vector_size(32)));
#define QM3D_ALWAYS_INLINE __attribute__((always_inline)) inline

template <class T>
QM3D_ALWAYS_INLINE void load(T& v, const double* p) {
  std::memcpy(&v, p, sizeof v);
}
template <class T>
QM3D_ALWAYS_INLINE void store(double* p, const T& v) {
  std::memcpy(p, &v, sizeof v);
}

/// The vertical sums of a, b, a², b², ab at column x (T = double) or the columns from x (lanes):
/// over the window's rows in order from 0, as gaussian_filter's first pass.
template <class T>
QM3D_ALWAYS_INLINE void vertical_at(const double* const ra[], const double* const rb[], int x,
                                    double* const v[5]) {
  const Kernel& k = gaussian_kernel();
  T s[5] = {};
  for (int j = 0; j <= 2 * kRadius; ++j) {
    T pa, pb;
    load(pa, ra[j] + x);
    load(pb, rb[j] + x);
    const T w = T{} + k[j];
    s[0] += w * pa;
    s[1] += w * pb;
    s[2] += w * (pa * pa);
    s[3] += w * (pb * pb);
    s[4] += w * (pa * pb);
  }
  for (int q = 0; q < 5; ++q) store(v[q] + x, s[q]);
}

/// The horizontal sum at column x (or the columns from x) of the padded vertical sums v.
template <class T>
QM3D_ALWAYS_INLINE void horizontal_at(const double* v, int x, double* h) {
  const Kernel& k = gaussian_kernel();
  T s = {};
  for (int j = 0; j <= 2 * kRadius; ++j) {
    T c;
    load(c, v + x + j);
    s += (T{} + k[j]) * c;
  }
  store(h + x, s);
}

/// Both passes over a span of columns, W columns at a time, the rest one by one.
template <class W>
QM3D_ALWAYS_INLINE void vertical_span(const double* const ra[], const double* const rb[], int lo,
                                      int hi, double* const v[5]) {
  constexpr int n = sizeof(W) / sizeof(double);
  int x = lo;
  for (; x + n - 1 <= hi; x += n) vertical_at<W>(ra, rb, x, v);
  for (; x <= hi; ++x) vertical_at<double>(ra, rb, x, v);
}
template <class W>
QM3D_ALWAYS_INLINE void horizontal_span(const double* v, int count, double* h) {
  constexpr int n = sizeof(W) / sizeof(double);
  int x = 0;
  for (; x + n - 1 < count; x += n) horizontal_at<W>(v, x, h);
  for (; x < count; ++x) horizontal_at<double>(v, x, h);
}

#if defined(__GNUC__) && defined(__x86_64__)
__attribute__((target("avx2"))) void vertical_span_avx2(const double* const ra[],
                                                        const double* const rb[], int lo, int hi,
                                                        double* const v[5]) {
  vertical_span<Lanes4>(ra, rb, lo, hi, v);
}
__attribute__((target("avx2"))) void horizontal_span_avx2(const double* v, int count, double* h) {
  horizontal_span<Lanes4>(v, count, h);
}
#else
void vertical_span_avx2(const double* const ra[], const double* const rb[], int lo, int hi,
                        double* const v[5]) {
  vertical_span<Lanes>(ra, rb, lo, hi, v);
}
void horizontal_span_avx2(const double* v, int count, double* h) {
  horizontal_span<Lanes>(v, count, h);
}
#endif

}  // namespace

namespace detail {

/// One scale of the pyramid: its ring of rows, the filtered sums of the row being scored (the
/// five quantities a, b, a², b², ab: vertical pass over the columns the mask's span reaches,
/// padded by kRadius reflected columns, then the horizontal pass) and the pooled sums.
struct SsimStream::Scale {
  int width = 0, height = 0, received = 0, scored = 0;
  std::vector<double> a, b;
  std::vector<std::uint8_t> mask;
  std::vector<double> vertical[5], horizontal[5];
  std::vector<double> half_a, half_b;  // the next scale's row being made
  std::vector<std::uint8_t> half_mask;
  double ssim_sum = 0, cs_sum = 0, l_sum = 0;
  std::size_t count = 0;

  void begin(int w, int h) {
    width = w, height = h, received = scored = 0;
    ssim_sum = cs_sum = l_sum = 0, count = 0;
    const std::size_t ring = static_cast<std::size_t>(kRingRows) * static_cast<std::size_t>(w);
    a.resize(ring), b.resize(ring), mask.resize(ring);
    for (auto& v : vertical) v.resize(static_cast<std::size_t>(w) + 2 * kRadius);
    for (auto& v : horizontal) v.resize(static_cast<std::size_t>(w));
    half_a.resize(static_cast<std::size_t>(w / 2)), half_b.resize(static_cast<std::size_t>(w / 2));
    half_mask.resize(static_cast<std::size_t>(w / 2));
  }
  std::size_t row(int y) const {
    return static_cast<std::size_t>(y % kRingRows) * static_cast<std::size_t>(width);
  }
  /// gaussian_filter's first pass over columns [lo, hi] (the same sums in the same order), then
  /// the columns beyond the image's edges reflected into the padding.
  void vertical_pass(int y, int lo, int hi) {
    const double* ra[2 * kRadius + 1];
    const double* rb[2 * kRadius + 1];
    for (int j = -kRadius; j <= kRadius; ++j) {
      const std::size_t r = row(reflect(y + j, height));
      ra[j + kRadius] = &a[r];
      rb[j + kRadius] = &b[r];
    }
    double* v[5];
    for (int q = 0; q < 5; ++q) v[q] = vertical[q].data() + kRadius;
    if (cpu_has_avx2()) {
      vertical_span_avx2(ra, rb, lo, hi, v);
    } else {
      vertical_span<Lanes>(ra, rb, lo, hi, v);
    }
    for (int q = 0; q < 5; ++q) {
      if (lo == 0) {
        for (int c = -kRadius; c < 0; ++c) v[q][c] = v[q][reflect(c, width)];
      }
      if (hi == width - 1) {
        for (int c = width; c < width + kRadius; ++c) v[q][c] = v[q][reflect(c, width)];
      }
    }
  }
  /// The second pass at columns [first, last]: at each column the sum over the window's columns
  /// in order, as gaussian_filter's second pass.
  void horizontal_pass(int first, int last) {
    const int n = last - first + 1;
    for (int q = 0; q < 5; ++q) {
      double* h = horizontal[q].data();
      const double* v = vertical[q].data() + first;  // padded: column first - kRadius
      if (cpu_has_avx2()) {
        horizontal_span_avx2(v, n, h);
      } else {
        horizontal_span<Lanes>(v, n, h);
      }
    }
  }
  /// Scores row y: the terms at its mask pixels, summed in order (the pooled means' order).
  void score_row(int y, bool full_scale, bool coarsest) {
    const std::uint8_t* m = &mask[row(y)];
    int first = 0, last = width - 1;
    while (first < width && !m[first]) ++first;
    if (first == width) return;
    while (!m[last]) --last;
    vertical_pass(y, std::max(0, first - kRadius), std::min(width - 1, last + kRadius));
    horizontal_pass(first, last);
    for (int x = first; x <= last; ++x) {
      if (!m[x]) continue;
      const std::size_t i = static_cast<std::size_t>(x - first);
      PixelStats s;
      s.mu_a = horizontal[0][i];
      s.mu_b = horizontal[1][i];
      s.var_a = horizontal[2][i] - s.mu_a * s.mu_a;
      s.var_b = horizontal[3][i] - s.mu_b * s.mu_b;
      s.cov = horizontal[4][i] - s.mu_a * s.mu_b;
      if (full_scale) ssim_sum += ssim_pixel_term(s);
      cs_sum += contrast_structure_term(s);
      if (coarsest) l_sum += luminance_term(s);
      ++count;
    }
  }
  /// The 2 x 2 block means of rows 2k, 2k + 1 (the last received), as halve / halve_mask did:
  /// an odd last column dropped, a block in the mask when all four pixels are.
  void halve_last_rows() {
    const std::size_t r0 = row(received - 2), r1 = row(received - 1);
    for (int x = 0; x < width / 2; ++x) {
      const std::size_t i = r0 + 2 * static_cast<std::size_t>(x),
                        j = r1 + 2 * static_cast<std::size_t>(x);
      half_a[x] = (a[i] + a[i + 1] + a[j] + a[j + 1]) / 4;
      half_b[x] = (b[i] + b[i + 1] + b[j] + b[j + 1]) / 4;
      half_mask[x] = mask[i] && mask[i + 1] && mask[j] && mask[j + 1];
    }
  }
};

SsimStream::SsimStream() {
  for (int j = 0; j < kMsSsimScales; ++j) scales_.push_back(std::make_unique<Scale>());
}
SsimStream::~SsimStream() = default;

void SsimStream::begin(int width, int height) {
  for (auto& s : scales_) {
    s->begin(width, height);
    width /= 2, height /= 2;
  }
}

void SsimStream::push_row(const double* a, const double* b, const std::uint8_t* mask) {
  push(0, a, b, mask);
}

void SsimStream::push(int scale, const double* a, const double* b, const std::uint8_t* mask) {
  Scale& s = *scales_[static_cast<std::size_t>(scale)];
  if (s.received >= s.height) throw std::logic_error("SSIM: more rows than the image has");
  const std::size_t r = s.row(s.received), w = static_cast<std::size_t>(s.width);
  std::copy(a, a + w, s.a.begin() + static_cast<std::ptrdiff_t>(r));
  std::copy(b, b + w, s.b.begin() + static_cast<std::ptrdiff_t>(r));
  std::copy(mask, mask + w, s.mask.begin() + static_cast<std::ptrdiff_t>(r));
  ++s.received;
  const bool coarsest = scale == kMsSsimScales - 1;
  while (s.scored < s.height && (s.scored + kRadius < s.received || s.received == s.height)) {
    s.score_row(s.scored++, scale == 0, coarsest);
  }
  if (!coarsest && s.received % 2 == 0 && s.received / 2 <= s.height / 2) {
    s.halve_last_rows();
    push(scale + 1, s.half_a.data(), s.half_b.data(), s.half_mask.data());
  }
}

SsimScores SsimStream::finish() const {
  const Scale& s0 = *scales_[0];
  SsimScores out;
  out.ssim = mean_or_nan(s0.ssim_sum, s0.count);
  double product = 1;
  for (int j = 0; j < kMsSsimScales; ++j) {
    const Scale& s = *scales_[static_cast<std::size_t>(j)];
    const double cs = mean_or_nan(s.cs_sum, s.count);
    if (std::isnan(cs)) {
      out.ms_ssim = cs;
      return out;
    }
    product *= std::pow(std::max(cs, 0.0), kMsSsimWeights[j]);
    if (j == kMsSsimScales - 1) {
      const double l = mean_or_nan(s.l_sum, s.count);
      product *= std::pow(std::max(l, 0.0), kMsSsimWeights[j]);
    }
  }
  out.ms_ssim = product;
  return out;
}

}  // namespace detail

std::vector<double> ssim_map(const GreyImage& a, const GreyImage& b) {
  check_sizes(a, b, nullptr);
  const LocalStats s = local_stats(a, b, Window{0, 0, a.width, a.height});
  std::vector<double> out(a.values.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = ssim_term(s, i);
  return out;
}

SsimScores masked_ssim_scores(const GreyImage& a, const GreyImage& b,
                              const std::vector<std::uint8_t>& mask) {
  check_sizes(a, b, &mask);
  detail::SsimStream stream;
  stream.begin(a.width, a.height);
  for (int y = 0; y < a.height; ++y) {
    const std::size_t r = static_cast<std::size_t>(y) * static_cast<std::size_t>(a.width);
    stream.push_row(&a.values[r], &b.values[r], &mask[r]);
  }
  return stream.finish();
}

double masked_ssim(const GreyImage& a, const GreyImage& b, const std::vector<std::uint8_t>& mask) {
  return masked_ssim_scores(a, b, mask).ssim;
}

double masked_ms_ssim(const GreyImage& a, const GreyImage& b,
                      const std::vector<std::uint8_t>& mask) {
  return masked_ssim_scores(a, b, mask).ms_ssim;
}

}  // namespace qm3d::render
