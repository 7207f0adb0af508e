// BatchFft (icid_fft.h): a mixed-radix Stockham FFT over kLanes sequences at once.
//
// Stage s of radix p combines the length-L transforms Y_L[k][j] (k < r = n / L: the transform
// of x[k], x[k + r], x[k + 2r], ... at frequency j) into length-pL ones: with r' = r / p,
//   Y_pL[k'][j + L s] = sum_t w_p^(s t) (w_pL^(j t) Y_L[k' + r' t][j]),
// Y_L[k][j] stored at element j r + k (Y_1 = x, Y_n = X in natural order). For fixed j and t the
// elements k' = 0 .. r' - 1, each kLanes doubles, are contiguous in input and output: the
// innermost loop runs over r' kLanes contiguous doubles.
#include "icid_fft.h"

#include <cmath>
#include <cstddef>
#include <utility>

namespace qm3d::render::icid_detail {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kLanes = BatchFft::kLanes;
// sin(2 pi / 3), the radix-3 butterfly's constant.
constexpr double kSin60 = 0.86602540378443864676;

#define QM3D_ICID_CLONES __attribute__((target_clones("avx2", "default")))
#define QM3D_INLINE __attribute__((always_inline)) inline
// A stage's inputs and outputs are distinct buffers and its outputs distinct elements: the
// compiler may vectorise the loop over the elements.
#define QM3D_LANES_INDEPENDENT _Pragma("GCC ivdep")

/// One stage's buffers and shape; the input and output never overlap.
struct StageIo {
  const double *xr, *xi;
  double *yr, *yi;
  int before, after;      // L, r'
  const double *wr, *wi;  // the stage's twiddles, radix - 1 per j
};

/// a * (wr + i wi), or a itself for the stage's first j (w = 1).
template <bool kTwiddle>
QM3D_INLINE void load(const double* xr, const double* xi, std::size_t e, double wr, double wi,
                      double& ar, double& ai) {
  if (kTwiddle) {
    ar = xr[e] * wr - xi[e] * wi;
    ai = xr[e] * wi + xi[e] * wr;
  } else {
    ar = xr[e];
    ai = xi[e];
  }
}

template <bool kTwiddle>
QM3D_INLINE void radix2_block(const StageIo& s, int j) {
  const std::size_t span = static_cast<std::size_t>(s.after) * kLanes;
  const std::size_t in = static_cast<std::size_t>(j) * 2 * span, out = j * span;
  const std::size_t step = static_cast<std::size_t>(s.before) * span;
  const double* x0r = s.xr + in;
  const double* x0i = s.xi + in;
  const double* x1r = x0r + span;
  const double* x1i = x0i + span;
  double* y0r = s.yr + out;
  double* y0i = s.yi + out;
  double* y1r = y0r + step;
  double* y1i = y0i + step;
  const double w1r = s.wr[j], w1i = s.wi[j];
  QM3D_LANES_INDEPENDENT
  for (std::size_t e = 0; e < span; ++e) {
    double br, bi;
    load<kTwiddle>(x1r, x1i, e, w1r, w1i, br, bi);
    const double ar = x0r[e], ai = x0i[e];
    y0r[e] = ar + br;
    y0i[e] = ai + bi;
    y1r[e] = ar - br;
    y1i[e] = ai - bi;
  }
}

template <bool kTwiddle>
QM3D_INLINE void radix4_block(const StageIo& s, int j) {
  const std::size_t span = static_cast<std::size_t>(s.after) * kLanes;
  const std::size_t in = static_cast<std::size_t>(j) * 4 * span, out = j * span;
  const std::size_t step = static_cast<std::size_t>(s.before) * span;
  const double* x0r = s.xr + in;
  const double* x0i = s.xi + in;
  const double* x1r = x0r + span;
  const double* x1i = x0i + span;
  const double* x2r = x1r + span;
  const double* x2i = x1i + span;
  const double* x3r = x2r + span;
  const double* x3i = x2i + span;
  double* y0r = s.yr + out;
  double* y0i = s.yi + out;
  double* y1r = y0r + step;
  double* y1i = y0i + step;
  double* y2r = y1r + step;
  double* y2i = y1i + step;
  double* y3r = y2r + step;
  double* y3i = y2i + step;
  const double w1r = s.wr[3 * j], w2r = s.wr[3 * j + 1], w3r = s.wr[3 * j + 2];
  const double w1i = s.wi[3 * j], w2i = s.wi[3 * j + 1], w3i = s.wi[3 * j + 2];
  QM3D_LANES_INDEPENDENT
  for (std::size_t e = 0; e < span; ++e) {
    const double a0r = x0r[e], a0i = x0i[e];
    double a1r, a1i, a2r, a2i, a3r, a3i;
    load<kTwiddle>(x1r, x1i, e, w1r, w1i, a1r, a1i);
    load<kTwiddle>(x2r, x2i, e, w2r, w2i, a2r, a2i);
    load<kTwiddle>(x3r, x3i, e, w3r, w3i, a3r, a3i);
    const double t0r = a0r + a2r, t0i = a0i + a2i, t1r = a0r - a2r, t1i = a0i - a2i;
    const double t2r = a1r + a3r, t2i = a1i + a3i, t3r = a1r - a3r, t3i = a1i - a3i;
    y0r[e] = t0r + t2r;  // w_4 = -i
    y0i[e] = t0i + t2i;
    y1r[e] = t1r + t3i;
    y1i[e] = t1i - t3r;
    y2r[e] = t0r - t2r;
    y2i[e] = t0i - t2i;
    y3r[e] = t1r - t3i;
    y3i[e] = t1i + t3r;
  }
}

// 1 / sqrt(2), w_8's real part.
constexpr double kHalfSqrt2 = 0.70710678118654752440;

/// One radix-4 DFT in registers (w_4 = -i), inputs b0..b3, outputs in place.
QM3D_INLINE void dft4(double& b0r, double& b0i, double& b1r, double& b1i, double& b2r, double& b2i,
                      double& b3r, double& b3i) {
  const double t0r = b0r + b2r, t0i = b0i + b2i, t1r = b0r - b2r, t1i = b0i - b2i;
  const double t2r = b1r + b3r, t2i = b1i + b3i, t3r = b1r - b3r, t3i = b1i - b3i;
  b0r = t0r + t2r;
  b0i = t0i + t2i;
  b1r = t1r + t3i;
  b1i = t1i - t3r;
  b2r = t0r - t2r;
  b2i = t0i - t2i;
  b3r = t1r - t3i;
  b3i = t1i + t3r;
}

/// Radix 8 as two radix-4 DFTs (even and odd inputs) and a radix-2 layer with w_8^s.
template <bool kTwiddle>
QM3D_INLINE void radix8_block(const StageIo& s, int j) {
  const std::size_t span = static_cast<std::size_t>(s.after) * kLanes;
  const std::size_t in = static_cast<std::size_t>(j) * 8 * span, out = j * span;
  const std::size_t step = static_cast<std::size_t>(s.before) * span;
  const double* xr = s.xr + in;
  const double* xi = s.xi + in;
  double* yr = s.yr + out;
  double* yi = s.yi + out;
  double wr[8], wi[8];
  for (int t = 1; t < 8; ++t) {
    wr[t] = s.wr[7 * j + t - 1];
    wi[t] = s.wi[7 * j + t - 1];
  }
  QM3D_LANES_INDEPENDENT
  for (std::size_t e = 0; e < span; ++e) {
    double ar[8], ai[8];
    ar[0] = xr[e];
    ai[0] = xi[e];
    for (int t = 1; t < 8; ++t)
      load<kTwiddle>(xr + t * span, xi + t * span, e, wr[t], wi[t], ar[t], ai[t]);
    dft4(ar[0], ai[0], ar[2], ai[2], ar[4], ai[4], ar[6], ai[6]);  // E_0..3 in 0, 2, 4, 6
    dft4(ar[1], ai[1], ar[3], ai[3], ar[5], ai[5], ar[7], ai[7]);  // O_0..3 in 1, 3, 5, 7
    // w_8^s O_s: s = 1: (1 - i) / sqrt2, s = 2: -i, s = 3: (-1 - i) / sqrt2
    const double o1r = (ar[3] + ai[3]) * kHalfSqrt2, o1i = (ai[3] - ar[3]) * kHalfSqrt2;
    const double o2r = ai[5], o2i = -ar[5];
    const double o3r = (ai[7] - ar[7]) * kHalfSqrt2, o3i = -(ar[7] + ai[7]) * kHalfSqrt2;
    yr[e] = ar[0] + ar[1];
    yi[e] = ai[0] + ai[1];
    yr[4 * step + e] = ar[0] - ar[1];
    yi[4 * step + e] = ai[0] - ai[1];
    yr[step + e] = ar[2] + o1r;
    yi[step + e] = ai[2] + o1i;
    yr[5 * step + e] = ar[2] - o1r;
    yi[5 * step + e] = ai[2] - o1i;
    yr[2 * step + e] = ar[4] + o2r;
    yi[2 * step + e] = ai[4] + o2i;
    yr[6 * step + e] = ar[4] - o2r;
    yi[6 * step + e] = ai[4] - o2i;
    yr[3 * step + e] = ar[6] + o3r;
    yi[3 * step + e] = ai[6] + o3i;
    yr[7 * step + e] = ar[6] - o3r;
    yi[7 * step + e] = ai[6] - o3i;
  }
}

/// Radix 3; with kMiddleOnly only the output s = 1 (the last stage of a centre-third inverse).
template <bool kTwiddle, bool kMiddleOnly>
QM3D_INLINE void radix3_block(const StageIo& s, int j) {
  const std::size_t span = static_cast<std::size_t>(s.after) * kLanes;
  const std::size_t in = static_cast<std::size_t>(j) * 3 * span, out = j * span;
  const std::size_t step = static_cast<std::size_t>(s.before) * span;
  const double* x0r = s.xr + in;
  const double* x0i = s.xi + in;
  const double* x1r = x0r + span;
  const double* x1i = x0i + span;
  const double* x2r = x1r + span;
  const double* x2i = x1i + span;
  double* y0r = s.yr + out;
  double* y0i = s.yi + out;
  double* y1r = y0r + step;
  double* y1i = y0i + step;
  double* y2r = y1r + step;
  double* y2i = y1i + step;
  const double w1r = s.wr[2 * j], w2r = s.wr[2 * j + 1];
  const double w1i = s.wi[2 * j], w2i = s.wi[2 * j + 1];
  QM3D_LANES_INDEPENDENT
  for (std::size_t e = 0; e < span; ++e) {
    const double a0r = x0r[e], a0i = x0i[e];
    double a1r, a1i, a2r, a2i;
    load<kTwiddle>(x1r, x1i, e, w1r, w1i, a1r, a1i);
    load<kTwiddle>(x2r, x2i, e, w2r, w2i, a2r, a2i);
    const double sr = a1r + a2r, si = a1i + a2i, dr = a1r - a2r, di = a1i - a2i;
    const double mr = a0r - 0.5 * sr, mi = a0i - 0.5 * si;
    // w_3 = -1/2 - i sin60: y1 = m - i sin60 d, y2 = m + i sin60 d
    y1r[e] = mr + kSin60 * di;
    y1i[e] = mi - kSin60 * dr;
    if (!kMiddleOnly) {
      y0r[e] = a0r + sr;
      y0i[e] = a0i + si;
      y2r[e] = mr - kSin60 * di;
      y2i[e] = mi + kSin60 * dr;
    }
  }
}

QM3D_ICID_CLONES void radix2_stage(const StageIo& s) {
  radix2_block<false>(s, 0);
  for (int j = 1; j < s.before; ++j) radix2_block<true>(s, j);
}

QM3D_ICID_CLONES void radix4_stage(const StageIo& s) {
  radix4_block<false>(s, 0);
  for (int j = 1; j < s.before; ++j) radix4_block<true>(s, j);
}

QM3D_ICID_CLONES void radix8_stage(const StageIo& s) {
  radix8_block<false>(s, 0);
  for (int j = 1; j < s.before; ++j) radix8_block<true>(s, j);
}

QM3D_ICID_CLONES void radix3_stage(const StageIo& s, bool middle_only) {
  if (middle_only) {
    radix3_block<false, true>(s, 0);
    for (int j = 1; j < s.before; ++j) radix3_block<true, true>(s, j);
  } else {
    radix3_block<false, false>(s, 0);
    for (int j = 1; j < s.before; ++j) radix3_block<true, false>(s, j);
  }
}

/// Any odd prime p <= kMaxRadix: y_s = sum_t w_p^(s t) a_t, the products added in t order.
void generic_stage(const StageIo& s, int p) {
  double cr[BatchFft::kMaxRadix], ci[BatchFft::kMaxRadix];
  for (int q = 0; q < p; ++q) {
    cr[q] = std::cos(2 * kPi * q / p);
    ci[q] = -std::sin(2 * kPi * q / p);
  }
  const std::size_t span = static_cast<std::size_t>(s.after) * kLanes;
  const std::size_t step = static_cast<std::size_t>(s.before) * span;
  double ar[BatchFft::kMaxRadix], ai[BatchFft::kMaxRadix];
  for (int j = 0; j < s.before; ++j) {
    const std::size_t in = static_cast<std::size_t>(j) * p * span, out = j * span;
    for (std::size_t e = 0; e < span; ++e) {
      ar[0] = s.xr[in + e];
      ai[0] = s.xi[in + e];
      for (int t = 1; t < p; ++t) {
        const double wr = s.wr[(p - 1) * j + t - 1], wi = s.wi[(p - 1) * j + t - 1];
        const double xr = s.xr[in + t * span + e], xi = s.xi[in + t * span + e];
        ar[t] = xr * wr - xi * wi;
        ai[t] = xr * wi + xi * wr;
      }
      for (int q = 0; q < p; ++q) {
        double yr = ar[0], yi = ai[0];
        for (int t = 1; t < p; ++t) {
          const int w = (q * t) % p;
          yr += ar[t] * cr[w] - ai[t] * ci[w];
          yi += ar[t] * ci[w] + ai[t] * cr[w];
        }
        s.yr[out + q * step + e] = yr;
        s.yi[out + q * step + e] = yi;
      }
    }
  }
}

/// n's prime factors, 8s first (then a 4 or a 2), the other odd primes, a 3 last when n has one.
std::vector<int> radices(int n) {
  std::vector<int> odd;
  int twos = 0;
  for (int p = 2; p <= n; ++p) {
    while (n % p == 0) {
      n /= p;
      if (p == 2) {
        ++twos;
      } else {
        odd.push_back(p);
      }
    }
  }
  // 8s, then a 4 or a 2 for what is left: 256 = 8 x 8 x 4 (three passes, not four)
  std::vector<int> out(twos / 3, 8);
  if (twos % 3 == 2) out.push_back(4);
  if (twos % 3 == 1) out.push_back(2);
  // the 3 (there is one when odd[0] == 3) moves to the end: odd is sorted, so it is the first
  if (!odd.empty() && odd.front() == 3) {
    out.insert(out.end(), odd.begin() + 1, odd.end());
    out.push_back(3);
  } else {
    out.insert(out.end(), odd.begin(), odd.end());
  }
  return out;
}

}  // namespace

bool BatchFft::supported(int n) {
  if (n < 1) return false;
  for (int p = 2; p <= kMaxRadix; ++p) {
    while (n % p == 0) n /= p;
  }
  return n == 1;
}

BatchFft::BatchFft(int n) : n_(n) {
  int before = 1;
  for (int p : radices(n)) {
    Stage s;
    s.radix = p;
    s.before = before;
    s.after = n / (before * p);
    const int length = before * p;
    for (int j = 0; j < before; ++j) {
      for (int t = 1; t < p; ++t) {
        // w_length^(j t), its exponent reduced mod length (the angle in [0, 2 pi))
        const double angle =
            -2 * kPi * static_cast<double>((static_cast<long long>(j) * t) % length) / length;
        s.twiddle_re.push_back(std::cos(angle));
        s.twiddle_im.push_back(std::sin(angle));
      }
    }
    stages_.push_back(std::move(s));
    before = length;
  }
}

bool BatchFft::run(double* xr, double* xi, double* yr, double* yi, bool centre_third) const {
  for (std::size_t k = 0; k < stages_.size(); ++k) {
    const Stage& st = stages_[k];
    const StageIo s{
        xr, xi, yr, yi, st.before, st.after, st.twiddle_re.data(), st.twiddle_im.data()};
    const bool last = k + 1 == stages_.size();
    if (st.radix == 8) {
      radix8_stage(s);
    } else if (st.radix == 4) {
      radix4_stage(s);
    } else if (st.radix == 2) {
      radix2_stage(s);
    } else if (st.radix == 3) {
      radix3_stage(s, centre_third && last);
    } else {
      generic_stage(s, st.radix);
    }
    std::swap(xr, yr);
    std::swap(xi, yi);
  }
  return stages_.size() % 2 == 1;
}

void BatchFft::forward(Buffers& b) const {
  if (run(b.re, b.im, b.work_re, b.work_im, false)) {
    std::swap(b.re, b.work_re);
    std::swap(b.im, b.work_im);
  }
}

void BatchFft::inverse_unscaled(Buffers& b) const {
  if (run(b.im, b.re, b.work_im, b.work_re, false)) {  // see inverse
    std::swap(b.re, b.work_re);
    std::swap(b.im, b.work_im);
  }
}

void BatchFft::inverse(Buffers& b, bool centre_third) const {
  // The inverse DFT is the forward one with the real and imaginary parts exchanged, on the way
  // in and out (swap(x) = i conj(x)).
  if (run(b.im, b.re, b.work_im, b.work_re, centre_third)) {
    std::swap(b.re, b.work_re);
    std::swap(b.im, b.work_im);
  }
  const double scale = 1.0 / n_;
  const std::size_t begin = centre_third ? static_cast<std::size_t>(n_ / 3) * kLanes : 0;
  const std::size_t end = centre_third ? static_cast<std::size_t>(2 * (n_ / 3)) * kLanes
                                       : static_cast<std::size_t>(n_) * kLanes;
  for (std::size_t e = begin; e < end; ++e) {
    b.re[e] *= scale;
    b.im[e] *= scale;
  }
}

}  // namespace qm3d::render::icid_detail
