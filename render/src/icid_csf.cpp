// iCID's contrast-sensitivity filtering (icid_csf.h), written from SPEC-ICID step 4: the CSFs of
// Reinhard, Khan, Akyuz & Johnson, "Color Imaging: Fundamentals and Applications" (2008) as the
// reference (Netflix/vmaf @ f85a853, matlab/cid_icid/iCID/iCID_Metric/ColorSpaceTransformations/
// FilterImageCSF.m) modifies them, applied in the frequency domain to the image padded
// symmetrically to 3x its size. FFT: qm3d's BatchFft (icid_fft.h) on pruned transforms of the
// padded lines (filter_channel_pair_pruned); sides with a prime factor above
// BatchFft::kMaxRadix go through Eigen's unsupported FFT module (its kissfft backend,
// BSD-3-Clause, Debian libeigen3-dev) on the full padded lines.
#include "icid_csf.h"

#include <omp.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <type_traits>
#include <unsupported/Eigen/FFT>
#include <utility>

#include "icid_fft.h"

namespace qm3d::render::icid_detail {
namespace {

using Complex = std::complex<double>;

// Cycles per degree at each axis's Nyquist frequency (iCID.m Options.CyclesPerDegree = 20).
constexpr double kCyclesPerDegree = 20;
// The padded image is 3x the image along each axis (FilterImageCSF 'pad_image' = 'both':
// padarray(., [M N], 'symmetric', 'both')).
constexpr int kPadFactor = 3;
// Columns moved together between the row-major spectra and the column pass (whole cache lines).
constexpr int kColumnBlock = 8;
constexpr double kTwoPi = 6.28318530717958647692;

// XYZ -> YCC (RIT), Reinhard et al. (FilterImageCSF.m M_TF); the way back solves with it.
constexpr double kXyzToYcc[3][3] = {
    {0.0556, 0.9981, -0.0254}, {0.9510, -0.9038, 0.0}, {0.0386, 1.0822, -1.0276}};

// Luminance CSF a f^c exp(-b f), made low-pass by the reference: 1 up to its second crossing of
// 1 at 13.3395 cpd (FilterImageCSF.m CSF_lum).
constexpr double kLumA = 0.63, kLumB = 0.085, kLumC = 0.616, kLumClip = 13.3395;

// Chromatic CSFs (a1 e^(-b1 f^c1) + a2 e^(-b2 f^c2)) / (a1 + a2): 1 at f = 0
// (FilterImageCSF.m CSF_rg, CSF_by).
struct ChromaCsf {
  double a1, b1, c1, a2, b2, c2;
};
constexpr ChromaCsf kRedGreen{91.228, 0.0003, 2.803, 74.907, 0.0038, 2.601};
constexpr ChromaCsf kBlueYellow{5.623, 0.00001, 3.4066, 41.9363, 0.083, 1.3684};

double csf_luminance(double f) {
  return f <= kLumClip ? 1.0 : kLumA * std::pow(f, kLumC) * std::exp(-kLumB * f);
}

double csf_chroma(const ChromaCsf& c, double f) {
  return (c.a1 * std::exp(-c.b1 * std::pow(f, c.c1)) + c.a2 * std::exp(-c.b2 * std::pow(f, c.c2))) /
         (c.a1 + c.a2);
}

/// The three filters on the padded size's frequency grid. The reference's grid (fftshift order)
/// holds along each axis of n samples the offsets from DC divided by their largest, floor(n/2):
/// at the unshifted index k that is min(k, n - k) / floor(n / 2), so each axis's Nyquist is at
/// 1 whatever n, and f = 20 sqrt(dx^2 + dy^2) cpd. The filters depend on min(k, n - k) only:
/// they are kept on that quarter of the grid, (n_rows / 2 + 1) x (n_cols / 2 + 1), column by
/// column.
struct CsfTables {
  int quarter_rows = 0;
  std::array<std::vector<double>, 3> values;  ///< luminance, red-green, blue-yellow
  /// Column l_folded of a channel's table, k_folded = 0 .. quarter_rows - 1 contiguous (the
  /// column pass reads it down a column).
  const double* column(int channel, int l_folded) const {
    return &values[channel][static_cast<std::size_t>(l_folded) * quarter_rows];
  }
};

CsfTables make_tables(int padded_rows, int padded_cols) {
  CsfTables t;
  t.quarter_rows = padded_rows / 2 + 1;
  const int qc = padded_cols / 2 + 1;
  for (auto& v : t.values) v.resize(static_cast<std::size_t>(t.quarter_rows) * qc);
  const double row_norm = padded_rows / 2, col_norm = padded_cols / 2;
  for (int l = 0; l < qc; ++l) {
    const double dx = l / col_norm;
    for (int k = 0; k < t.quarter_rows; ++k) {
      const double dy = k / row_norm;
      const double f = std::sqrt(dx * dx + dy * dy) * kCyclesPerDegree;
      const std::size_t i = static_cast<std::size_t>(l) * t.quarter_rows + k;
      t.values[0][i] = csf_luminance(f);
      t.values[1][i] = csf_chroma(kRedGreen, f);
      t.values[2][i] = csf_chroma(kBlueYellow, f);
    }
  }
  return t;
}

/// The tables of a padded size, computed once per size (the views of a metric share one).
std::shared_ptr<const CsfTables> tables_for(int padded_rows, int padded_cols) {
  static std::mutex mutex;
  static std::map<std::pair<int, int>, std::shared_ptr<const CsfTables>> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[{padded_rows, padded_cols}];
  if (!slot) slot = std::make_shared<const CsfTables>(make_tables(padded_rows, padded_cols));
  return slot;
}

/// The DFT of one length, forwards (unscaled) and backwards (scaled by 1 / n), as the
/// reference's fft2 / ifft2 along an axis. Eigen's kissfft when the length has only small prime
/// factors; kissfft's generic radix costs p^2 per prime factor p (a 257-pixel side: 771 = 3 x 257),
/// so a length with a prime factor above kMaxKissPrime goes through Bluestein's algorithm
/// (Bluestein 1970: the DFT as a convolution with the chirp w_k = exp(-i pi k^2 / n), done by
/// FFTs of a length >= 2n - 1 with prime factors 2, 3, 5; exact to rounding, ~1e-16 of the
/// largest value).
class LineFft {
 public:
  static constexpr int kMaxKissPrime = 64;

  explicit LineFft(int n) : n_(n) {
    if (largest_prime_factor(n) <= kMaxKissPrime) return;
    m_ = 2 * n - 1;
    while (largest_prime_factor(m_) > 5) ++m_;  // kissfft's fast radices 2, 3, 4, 5
    chirp_.resize(n);
    for (long long k = 0; k < n; ++k) {
      const double angle = -kPi * static_cast<double>((k * k) % (2LL * n)) / n;
      chirp_[k] = Complex(std::cos(angle), std::sin(angle));
    }
    std::vector<Complex> b(m_, Complex(0, 0));
    for (int k = 0; k < n; ++k) b[k] = std::conj(chirp_[k]);
    for (int k = 1; k < n; ++k) b[m_ - k] = std::conj(chirp_[k]);
    kernel_.resize(m_);
    fft_.fwd(kernel_.data(), b.data(), m_);
    a_.resize(m_);
    spectrum_.resize(m_);
  }

  void forward(Complex* out, const Complex* in) {
    if (m_ == 0) return fft_.fwd(out, in, n_);
    std::fill(a_.begin(), a_.end(), Complex(0, 0));
    for (int k = 0; k < n_; ++k) a_[k] = in[k] * chirp_[k];
    fft_.fwd(spectrum_.data(), a_.data(), m_);
    for (int k = 0; k < m_; ++k) spectrum_[k] *= kernel_[k];
    fft_.inv(a_.data(), spectrum_.data(), m_);  // scaled by 1 / m
    for (int k = 0; k < n_; ++k) out[k] = a_[k] * chirp_[k];
  }

  void inverse(Complex* out, const Complex* in) {
    if (m_ == 0) return fft_.inv(out, in, n_);
    conj_.resize(n_);
    for (int k = 0; k < n_; ++k) conj_[k] = std::conj(in[k]);
    forward(out, conj_.data());
    const double scale = 1.0 / n_;
    for (int k = 0; k < n_; ++k) out[k] = std::conj(out[k]) * scale;
  }

 private:
  static constexpr double kPi = 3.14159265358979323846;

  static int largest_prime_factor(int n) {
    int largest = 1;
    for (int p = 2; p * p <= n; ++p) {
      while (n % p == 0) largest = p, n /= p;
    }
    return std::max(largest, n);
  }

  int n_ = 0, m_ = 0;  // m_ = 0: kissfft directly
  Eigen::FFT<double> fft_;
  std::vector<Complex> chirp_, kernel_, a_, spectrum_, conj_;
};

/// padarray's 'symmetric' border: index i in [-n, 2n) of the padded axis -> the image's index.
int mirror(int i, int n) { return i < 0 ? -1 - i : (i >= n ? 2 * n - 1 - i : i); }

int thread_count(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

/// One channel of both images filtered in place. The CSF is real and even, so the filtered
/// padded image stays real: image a travels as the real part and image b as the imaginary part
/// of one complex FFT. Of the padded image's 3 x rows only `rows` differ (mirrored copies), so
/// only those rows are transformed first; the column pass transforms every column forwards,
/// filters and back (kColumnBlock columns gathered at a time); the last pass transforms back only
/// the rows of the centre crop.
void filter_channel_pair(std::vector<double>& a, std::vector<double>& b, int rows, int cols,
                         const CsfTables& h, int channel, int threads) {
  const int nr = kPadFactor * rows, nc = kPadFactor * cols;
  std::vector<Complex> spectra(static_cast<std::size_t>(rows) * nc);
  std::vector<Complex> crop(static_cast<std::size_t>(rows) * nc);
#pragma omp parallel num_threads(thread_count(threads))
  {
    LineFft row_fft(nc), column_fft(nr);  // one per thread: they cache their plans
    std::vector<Complex> in(nc), out(std::max(nr, nc));
    std::vector<Complex> block(static_cast<std::size_t>(kColumnBlock) * nr);
#pragma omp for schedule(static)
    for (int y = 0; y < rows; ++y) {
      const std::size_t row = static_cast<std::size_t>(y) * cols;
      for (int q = 0; q < nc; ++q) {
        const std::size_t i = row + mirror(q - cols, cols);
        in[q] = Complex(a[i], b[i]);
      }
      row_fft.forward(&spectra[static_cast<std::size_t>(y) * nc], in.data());
    }
#pragma omp for schedule(static)
    for (int l0 = 0; l0 < nc; l0 += kColumnBlock) {
      const int width = std::min(kColumnBlock, nc - l0);
      for (int y = 0; y < rows;
           ++y) {  // each row lands at padded rows M + y, M - 1 - y, 3M - 1 - y
        const Complex* src = &spectra[static_cast<std::size_t>(y) * nc + l0];
        for (int c = 0; c < width; ++c) {
          Complex* column = &block[static_cast<std::size_t>(c) * nr];
          column[rows + y] = column[rows - 1 - y] = column[3 * rows - 1 - y] = src[c];
        }
      }
      for (int c = 0; c < width; ++c) {
        Complex* column = &block[static_cast<std::size_t>(c) * nr];
        column_fft.forward(out.data(), column);
        const double* filter = h.column(channel, std::min(l0 + c, nc - l0 - c));
        for (int k = 0; k < nr; ++k) out[k] *= filter[std::min(k, nr - k)];
        column_fft.inverse(column, out.data());  // scaled by 1 / nr
      }
      for (int p = 0; p < rows; ++p) {
        Complex* dst = &crop[static_cast<std::size_t>(p) * nc + l0];
        for (int c = 0; c < width; ++c) dst[c] = block[static_cast<std::size_t>(c) * nr + rows + p];
      }
    }
#pragma omp for schedule(static)
    for (int y = 0; y < rows; ++y) {
      row_fft.inverse(out.data(), &crop[static_cast<std::size_t>(y) * nc]);  // scaled by 1 / nc
      const std::size_t row = static_cast<std::size_t>(y) * cols;
      for (int x = 0; x < cols; ++x) {
        a[row + x] = out[cols + x].real();
        b[row + x] = out[cols + x].imag();
      }
    }
  }
}

/// The plan of a length, made once (plans are immutable; the views of a metric share them).
std::shared_ptr<const BatchFft> batch_plan(int n) {
  static std::mutex mutex;
  static std::map<int, std::shared_ptr<const BatchFft>> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[n];
  if (!slot) slot = std::make_shared<const BatchFft>(n);
  return slot;
}

constexpr int kLanes = BatchFft::kLanes;

/// A frequency index k of an axis of n samples -> the CSF tables' min(k, n - k).
int fold(int k, int n) { return std::min(k, n - k); }

/// A thread's buffers for BatchFft: a block of kLanes sequences and the transform's work space.
struct LaneBuffers {
  std::vector<double> re, im, work_re, work_im;
  explicit LaneBuffers(int n)
      : re(static_cast<std::size_t>(n) * kLanes),
        im(re.size()),
        work_re(re.size()),
        work_im(re.size()) {}
  void clear() {
    std::fill(re.begin(), re.end(), 0.0);
    std::fill(im.begin(), im.end(), 0.0);
  }
  /// The block as BatchFft's buffers: the sequences in (re, im).
  BatchFft::Buffers io() { return {re.data(), im.data(), work_re.data(), work_im.data()}; }
};

// The padded transforms, pruned. Along an axis of n samples the padded sequence is
// p = [flip(x), x, flip(x)] (3n samples); with w = exp(-2 pi i / 3n), splitting its DFT by the
// frequency's residue mod 3 (radix-3 decimation in frequency, p's thirds folded in):
//   P[3m]     = DFT_n(u)[m],  u_q = x_q + 2 x_(n-1-q),
//   P[3m + 1] = DFT_n(v)[m],  v_q = w^(n + q) (x_q - x_(n-1-q)),
//   P[3n - k] = -w^k P[k] for k != 0 mod 3 (p_q + p_(-1-q) has period n),
// so the lines k = 3m + 2 follow from the lines k = 3m + 1. A filter even along the axis
// (H[k] = H[3n - k], the CSFs) keeps that relation, and the centre third of the filtered
// sequence's inverse DFT, from the unscaled inverse DFTs I0 of the lines 3m and I1 of the lines
// 3m + 1 (each of n points), is
//   y_(n+p) = (I0_p + w^(-(n + p)) I1_p - w^(n + 1 + p) I1_(n-1-p)) / 3n.
// In two dimensions the relation holds along each axis separately (the CSF depends on
// min(k, 3n - k) along each), so of the padded 3M x 3N spectrum only the 2M x 2N lines with
// k, l != 2 mod 3 are transformed: n-point FFTs (in cache, radix 4) of 2/3 of the lines, about
// half the butterflies of the full 3n-point ones. The FFT's summation order is free (1e-10 of
// the reference, whose FFTW differs from any of ours in the last bits anyway).

/// The pre- and post-twiddles of the pruned transforms along an axis of n samples, and the
/// n-point plan.
struct PaddedAxis {
  int n = 0;
  std::shared_ptr<const BatchFft> plan;
  std::vector<double> pre_re, pre_im;      ///< w^(n + q)
  double post0 = 0;                        ///< 1 / 3n
  std::vector<double> post1_re, post1_im;  ///< w^(-(n + p)) / 3n
  std::vector<double> post2_re, post2_im;  ///< -w^(n + 1 + p) / 3n
};

PaddedAxis make_padded_axis(int n) {
  PaddedAxis ax;
  ax.n = n;
  ax.plan = batch_plan(n);
  ax.post0 = 1.0 / (3.0 * n);  // the inverse n-point DFTs come unscaled
  const long long period = 3LL * n;
  // w^e, the exponent reduced to [0, 3n) (the angle in [0, 2 pi))
  auto power = [period](long long e, double scale, std::vector<double>& re,
                        std::vector<double>& im) {
    const double angle = -kTwoPi * static_cast<double>(((e % period) + period) % period) /
                         static_cast<double>(period);
    re.push_back(scale * std::cos(angle));
    im.push_back(scale * std::sin(angle));
  };
  for (int q = 0; q < n; ++q) {
    power(n + q, 1.0, ax.pre_re, ax.pre_im);
    power(-(n + q), ax.post0, ax.post1_re, ax.post1_im);
    power(n + 1 + q, -ax.post0, ax.post2_re, ax.post2_im);
  }
  return ax;
}

std::shared_ptr<const PaddedAxis> padded_axis(int n) {
  static std::mutex mutex;
  static std::map<int, std::shared_ptr<const PaddedAxis>> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[n];
  if (!slot) slot = std::make_shared<const PaddedAxis>(make_padded_axis(n));
  return slot;
}

/// kLanes sequences, each contiguous in memory (lane c's element q at re[c][q], im[c][q]).
struct LaneLines {
  const double* re[kLanes];
  const double* im[kLanes];
};
struct LaneLinesOut {
  double* re[kLanes];
  double* im[kLanes];
};

/// A block's two halves: the lines 3m (u) and 3m + 1 (v).
struct PrunedBlock {
  LaneBuffers u, v;
  BatchFft::Buffers u_io{}, v_io{};
  explicit PrunedBlock(int n) : u(n), v(n) {}
  void start(int lanes) {
    if (lanes < kLanes) {
      u.clear();
      v.clear();
    }
    u_io = u.io();
    v_io = v.io();
  }
};

// A full block's lines move between their own contiguous storage and the lane layout in
// 4 x 4 tiles transposed in registers (GCC/clang vector types and __builtin_shufflevector,
// which both compilers have; the same arithmetic, element by element, as the scalar loops
// that serve partial blocks).
static_assert(kLanes == 4, "the tiles are kLanes x 4");
typedef double Tile4 __attribute__((vector_size(32), aligned(8), may_alias));

/// r[c][t] -> r[t][c].
__attribute__((always_inline)) inline void transpose(Tile4 r[4]) {
  const Tile4 t0 = __builtin_shufflevector(r[0], r[1], 0, 4, 2, 6);
  const Tile4 t1 = __builtin_shufflevector(r[0], r[1], 1, 5, 3, 7);
  const Tile4 t2 = __builtin_shufflevector(r[2], r[3], 0, 4, 2, 6);
  const Tile4 t3 = __builtin_shufflevector(r[2], r[3], 1, 5, 3, 7);
  r[0] = __builtin_shufflevector(t0, t2, 0, 1, 4, 5);
  r[1] = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
  r[2] = __builtin_shufflevector(t0, t2, 2, 3, 6, 7);
  r[3] = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
}

/// Elements q0 .. q0 + 3 of the four lines of `lines` as four lane vectors.
__attribute__((always_inline)) inline void load_tile(const double* const lines[kLanes], int q0,
                                                     Tile4 r[4]) {
  for (int c = 0; c < kLanes; ++c) r[c] = *reinterpret_cast<const Tile4*>(lines[c] + q0);
  transpose(r);
}

/// u and v of a full block (n a multiple of 4).
__attribute__((target_clones("avx2", "default"))) void analyse_tiles(const PaddedAxis& ax,
                                                                     const LaneLines& x,
                                                                     PrunedBlock& blk) {
  const int n = ax.n;
  for (int q0 = 0; q0 < n; q0 += 4) {
    Tile4 xr[4], xi[4], fr[4], fi[4];  // fr[3 - t]: element n - 1 - (q0 + t)
    load_tile(x.re, q0, xr);
    load_tile(x.im, q0, xi);
    load_tile(x.re, n - 4 - q0, fr);
    load_tile(x.im, n - 4 - q0, fi);
    for (int t = 0; t < 4; ++t) {
      const int q = q0 + t;
      const std::size_t e = static_cast<std::size_t>(q) * kLanes;
      const Tile4 f_re = fr[3 - t], f_im = fi[3 - t];
      *reinterpret_cast<Tile4*>(blk.u_io.re + e) = xr[t] + 2.0 * f_re;
      *reinterpret_cast<Tile4*>(blk.u_io.im + e) = xi[t] + 2.0 * f_im;
      const Tile4 dr = xr[t] - f_re, di = xi[t] - f_im;
      *reinterpret_cast<Tile4*>(blk.v_io.re + e) = dr * ax.pre_re[q] - di * ax.pre_im[q];
      *reinterpret_cast<Tile4*>(blk.v_io.im + e) = dr * ax.pre_im[q] + di * ax.pre_re[q];
    }
  }
}

/// u and v of `lanes` sequences of ax.n samples, forward transformed.
void analyse(const PaddedAxis& ax, const LaneLines& x, int lanes, PrunedBlock& blk) {
  const int n = ax.n;
  blk.start(lanes);
  if (lanes == kLanes && n % 4 == 0) {
    analyse_tiles(ax, x, blk);
  } else {
    for (int c = 0; c < lanes; ++c) {
      const double* xr = x.re[c];
      const double* xi = x.im[c];
      for (int q = 0; q < n; ++q) {
        const std::size_t e = static_cast<std::size_t>(q) * kLanes + c;
        const double fr = xr[n - 1 - q], fi = xi[n - 1 - q];
        blk.u_io.re[e] = xr[q] + 2.0 * fr;
        blk.u_io.im[e] = xi[q] + 2.0 * fi;
        const double dr = xr[q] - fr, di = xi[q] - fi;
        blk.v_io.re[e] = dr * ax.pre_re[q] - di * ax.pre_im[q];
        blk.v_io.im[e] = dr * ax.pre_im[q] + di * ax.pre_re[q];
      }
    }
  }
  ax.plan->forward(blk.u_io);
  ax.plan->forward(blk.v_io);
}

/// synthesise's combination for a full block (n a multiple of 4).
__attribute__((target_clones("avx2", "default"))) void synthesise_tiles(const PaddedAxis& ax,
                                                                        const PrunedBlock& blk,
                                                                        const LaneLinesOut& out) {
  const int n = ax.n;
  // element p of the lane layout: a Tile4 (kLanes doubles)
  const Tile4* i0r = reinterpret_cast<const Tile4*>(blk.u_io.re);
  const Tile4* i0i = reinterpret_cast<const Tile4*>(blk.u_io.im);
  const Tile4* i1r = reinterpret_cast<const Tile4*>(blk.v_io.re);
  const Tile4* i1i = reinterpret_cast<const Tile4*>(blk.v_io.im);
  for (int p0 = 0; p0 < n; p0 += 4) {
    Tile4 yr[4], yi[4];
    for (int t = 0; t < 4; ++t) {
      const int p = p0 + t, f = n - 1 - p;
      const double ar = ax.post1_re[p], ai = ax.post1_im[p];
      const double br = ax.post2_re[p], bi = ax.post2_im[p];
      yr[t] = i0r[p] * ax.post0 + (i1r[p] * ar - i1i[p] * ai) + (i1r[f] * br - i1i[f] * bi);
      yi[t] = i0i[p] * ax.post0 + (i1r[p] * ai + i1i[p] * ar) + (i1r[f] * bi + i1i[f] * br);
    }
    transpose(yr);
    transpose(yi);
    for (int c = 0; c < kLanes; ++c) {
      *reinterpret_cast<Tile4*>(out.re[c] + p0) = yr[c];
      *reinterpret_cast<Tile4*>(out.im[c] + p0) = yi[c];
    }
  }
}

/// The inverse transforms of a block holding the lines 3m (u) and 3m + 1 (v), and the centre
/// third of the padded sequences written to `out` (the first `lanes`).
void synthesise(const PaddedAxis& ax, PrunedBlock& blk, int lanes, const LaneLinesOut& out) {
  const int n = ax.n;
  ax.plan->inverse_unscaled(blk.u_io);
  ax.plan->inverse_unscaled(blk.v_io);
  if (lanes == kLanes && n % 4 == 0) return synthesise_tiles(ax, blk, out);
  const double* i0r = blk.u_io.re;
  const double* i0i = blk.u_io.im;
  const double* i1r = blk.v_io.re;
  const double* i1i = blk.v_io.im;
  for (int c = 0; c < lanes; ++c) {
    for (int p = 0; p < n; ++p) {
      const std::size_t e = static_cast<std::size_t>(p) * kLanes + c;
      const std::size_t f = static_cast<std::size_t>(n - 1 - p) * kLanes + c;
      const double ar = ax.post1_re[p], ai = ax.post1_im[p];
      const double br = ax.post2_re[p], bi = ax.post2_im[p];
      out.re[c][p] = i0r[e] * ax.post0 + (i1r[e] * ar - i1i[e] * ai) + (i1r[f] * br - i1i[f] * bi);
      out.im[c][p] = i0i[e] * ax.post0 + (i1r[e] * ai + i1i[e] * ar) + (i1r[f] * bi + i1i[f] * br);
    }
  }
}

/// The CSF on a column block's lines: line j of the row spectra is the padded frequency
/// l = 3j (j < cols) or 3 (j - cols) + 1; along the column, u holds k = 3m and v k = 3m + 1.
void filter_block(const CsfTables& h, int channel, int rows, int cols, int j0, int lanes,
                  PrunedBlock& blk) {
  const int nr = kPadFactor * rows, nc = kPadFactor * cols;
  const double* filter[kLanes];
  for (int c = 0; c < kLanes; ++c) {
    const int j = j0 + std::min(c, lanes - 1);
    const int l = j < cols ? 3 * j : 3 * (j - cols) + 1;
    filter[c] = h.column(channel, fold(l, nc));
  }
  for (int m = 0; m < rows; ++m) {
    const int k0 = fold(3 * m, nr), k1 = fold(3 * m + 1, nr);
    const std::size_t e = static_cast<std::size_t>(m) * kLanes;
    for (int c = 0; c < kLanes; ++c) {
      blk.u_io.re[e + c] *= filter[c][k0];
      blk.u_io.im[e + c] *= filter[c][k0];
      blk.v_io.re[e + c] *= filter[c][k1];
      blk.v_io.im[e + c] *= filter[c][k1];
    }
  }
}

/// The calling thread's block for lines of n samples (`which`: 0 the rows', 1 the columns'),
/// kept between calls up to kKeptBlockSide (fresh pages cost as much as the arithmetic at 256^2).
constexpr int kKeptBlockSide = 4096;
PrunedBlock& pruned_block(int n, int which) {
  static thread_local std::map<std::pair<int, int>, PrunedBlock> kept;
  static thread_local std::unique_ptr<PrunedBlock> large[2];
  if (n <= kKeptBlockSide) return kept.try_emplace({n, which}, n).first->second;
  large[which] = std::make_unique<PrunedBlock>(n);
  return *large[which];
}

/// f(kLanes as a compile-time constant) for a full block, f(lanes) otherwise: a full block's
/// copies get a constant size (vector moves).
template <class F>
void with_lanes(int lanes, F&& f) {
  if (lanes == kLanes) {
    f(std::integral_constant<int, kLanes>{});
  } else {
    f(lanes);
  }
}

/// filter_channel_pair with the pruned transforms (BatchFft supports both sides), kLanes rows or
/// lines at a time. The row spectra's 2 cols lines (3m, then 3m + 1) are kept line by line
/// (element j * rows + y). Lanes past the last row or line carry zeros and are not written back.
void filter_channel_pair_pruned(std::vector<double>& a, std::vector<double>& b, int rows, int cols,
                                const CsfTables& h, int channel, int threads,
                                std::vector<double>& spec_re, std::vector<double>& spec_im) {
  const auto row_axis = padded_axis(cols), column_axis = padded_axis(rows);
  const int lines = 2 * cols;
  spec_re.resize(static_cast<std::size_t>(rows) * lines);
  spec_im.resize(spec_re.size());
  const int row_blocks = (rows + kLanes - 1) / kLanes, line_blocks = (lines + kLanes - 1) / kLanes;
  auto at = [rows](std::vector<double>& v, int j, int y) {
    return &v[static_cast<std::size_t>(j) * rows + y];
  };
#pragma omp parallel num_threads(thread_count(threads))
  {
    PrunedBlock &row_blk = pruned_block(cols, 0), &column_blk = pruned_block(rows, 1);
#pragma omp for schedule(static)
    for (int block = 0; block < row_blocks; ++block) {
      const int y0 = block * kLanes, lanes = std::min(kLanes, rows - y0);
      LaneLines x{};
      for (int c = 0; c < lanes; ++c) {
        x.re[c] = &a[static_cast<std::size_t>(y0 + c) * cols];
        x.im[c] = &b[static_cast<std::size_t>(y0 + c) * cols];
      }
      analyse(*row_axis, x, lanes, row_blk);
      with_lanes(lanes, [&](auto count) {
        for (int m = 0; m < cols; ++m) {
          const std::size_t e = static_cast<std::size_t>(m) * kLanes;
          double *ur = at(spec_re, m, y0), *ui = at(spec_im, m, y0);
          double *vr = at(spec_re, cols + m, y0), *vi = at(spec_im, cols + m, y0);
          const std::size_t bytes = sizeof(double) * count;
          std::memcpy(ur, row_blk.u_io.re + e, bytes);
          std::memcpy(ui, row_blk.u_io.im + e, bytes);
          std::memcpy(vr, row_blk.v_io.re + e, bytes);
          std::memcpy(vi, row_blk.v_io.im + e, bytes);
        }
      });
    }
#pragma omp for schedule(static)
    for (int block = 0; block < line_blocks; ++block) {
      const int j0 = block * kLanes, lanes = std::min(kLanes, lines - j0);
      LaneLines x{};
      LaneLinesOut out{};
      for (int c = 0; c < lanes; ++c) {
        out.re[c] = at(spec_re, j0 + c, 0);
        out.im[c] = at(spec_im, j0 + c, 0);
        x.re[c] = out.re[c];
        x.im[c] = out.im[c];
      }
      analyse(*column_axis, x, lanes, column_blk);
      filter_block(h, channel, rows, cols, j0, lanes, column_blk);
      synthesise(*column_axis, column_blk, lanes, out);  // in place: the line was read
    }
#pragma omp for schedule(static)
    for (int block = 0; block < row_blocks; ++block) {
      const int y0 = block * kLanes, lanes = std::min(kLanes, rows - y0);
      row_blk.start(lanes);
      with_lanes(lanes, [&](auto count) {
        for (int m = 0; m < cols; ++m) {
          const std::size_t e = static_cast<std::size_t>(m) * kLanes;
          const double *ur = at(spec_re, m, y0), *ui = at(spec_im, m, y0);
          const double *vr = at(spec_re, cols + m, y0), *vi = at(spec_im, cols + m, y0);
          const std::size_t bytes = sizeof(double) * count;
          std::memcpy(row_blk.u_io.re + e, ur, bytes);
          std::memcpy(row_blk.u_io.im + e, ui, bytes);
          std::memcpy(row_blk.v_io.re + e, vr, bytes);
          std::memcpy(row_blk.v_io.im + e, vi, bytes);
        }
      });
      LaneLinesOut out{};
      for (int c = 0; c < lanes; ++c) {
        out.re[c] = &a[static_cast<std::size_t>(y0 + c) * cols];
        out.im[c] = &b[static_cast<std::size_t>(y0 + c) * cols];
      }
      synthesise(*row_axis, row_blk, lanes, out);
    }
  }
}

using Ycc = std::array<std::vector<double>, 3>;

/// XYZ -> YCC; the luminance's mean (mean2 of channel 1) subtracted and returned.
double to_ycc(const XyzPlanes& in, Ycc& out) {
  const std::size_t n = in.x.size();
  for (auto& c : out) c.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      out[c][i] = kXyzToYcc[c][0] * in.x[i] + kXyzToYcc[c][1] * in.y[i] + kXyzToYcc[c][2] * in.z[i];
    }
  }
  double sum = 0;
  for (double v : out[0]) sum += v;
  const double mean = sum / static_cast<double>(n);
  for (double& v : out[0]) v -= mean;
  return mean;
}

/// The luminance's mean added back; YCC -> XYZ (M_TF \ YCC).
void to_xyz(Ycc& in, double lum_mean, XyzPlanes& out) {
  static const Eigen::Matrix3d inverse = [] {
    Eigen::Matrix3d m;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m(r, c) = kXyzToYcc[r][c];
    }
    return Eigen::Matrix3d(m.inverse());
  }();
  for (std::size_t i = 0; i < in[0].size(); ++i) {
    const Eigen::Vector3d ycc(in[0][i] + lum_mean, in[1][i], in[2][i]);
    const Eigen::Vector3d xyz = inverse * ycc;
    out.x[i] = xyz[0];
    out.y[i] = xyz[1];
    out.z[i] = xyz[2];
  }
}

/// The filtering's planes (the YCC planes and the spectra, 12 of the image's size), kept by each
/// calling thread between calls for images up to kScratchPixels (fresh pages cost as much as a
/// fifth of the work at 256^2); larger images use planes of their own.
struct CsfScratch {
  Ycc ycc_a, ycc_b;
  std::vector<double> spec_re, spec_im;  // shared by the three channels
};
constexpr std::size_t kScratchPixels = std::size_t{1} << 19;

CsfScratch& csf_scratch() {
  static thread_local CsfScratch scratch;
  return scratch;
}

}  // namespace

namespace {

/// csf_filter; `pruned`: the pruned transforms where BatchFft supports both sides, else the
/// full 3n-point ones (LineFft).
void csf_filter_with(XyzPlanes& a, XyzPlanes& b, int threads, bool pruned) {
  const int rows = a.rows, cols = a.cols;
  const auto tables = tables_for(kPadFactor * rows, kPadFactor * cols);
  CsfScratch local;
  CsfScratch& scratch =
      static_cast<std::size_t>(rows) * cols <= kScratchPixels ? csf_scratch() : local;
  Ycc &ycc_a = scratch.ycc_a, &ycc_b = scratch.ycc_b;
  std::vector<double>&spec_re = scratch.spec_re, &spec_im = scratch.spec_im;
  const double mean_a = to_ycc(a, ycc_a), mean_b = to_ycc(b, ycc_b);
  const bool batched = pruned && BatchFft::supported(rows) && BatchFft::supported(cols);
  for (int c = 0; c < 3; ++c) {
    if (batched) {
      filter_channel_pair_pruned(ycc_a[c], ycc_b[c], rows, cols, *tables, c, threads, spec_re,
                                 spec_im);
    } else {
      filter_channel_pair(ycc_a[c], ycc_b[c], rows, cols, *tables, c, threads);
    }
  }
  to_xyz(ycc_a, mean_a, a);
  to_xyz(ycc_b, mean_b, b);
}

}  // namespace

void csf_filter(XyzPlanes& a, XyzPlanes& b, int threads) { csf_filter_with(a, b, threads, true); }

void csf_filter_full_transforms(XyzPlanes& a, XyzPlanes& b, int threads) {
  csf_filter_with(a, b, threads, false);
}

}  // namespace qm3d::render::icid_detail
