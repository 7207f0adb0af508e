// iCID (qm3d/render/icid.h), written from Preiss, Fernandes & Urban (IEEE TIP 2014) and
// SPEC-ICID, reproducing the authors' MATLAB code (iCID.m v1.00, Netflix/vmaf @ f85a853,
// matlab/cid_icid/iCID/iCID_Metric): each rule that decides a number is written where it lives.
#include "qm3d/render/icid.h"

#include <omp.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "icid_csf.h"

namespace qm3d::render {
namespace {

using icid_detail::XyzPlanes;

// Downsampling: f = max(1, round(min(M, N) / 256)) (iCID.m), MATLAB's round: half away from
// zero as std::round (384 -> 1.5 -> 2).
constexpr double kDownsamplingSide = 256;

// The maps' window: fspecial('gaussian', 11, 2), filter2 'valid' (iCID.m WindowSize, StdDev,
// Mode): a 5-pixel border of the (downsampled) image has no map.
constexpr int kWindowSize = 11;
constexpr int kWindowRadius = kWindowSize / 2;
constexpr double kWindowSigma = 2.0;

// CIELAB white point of Getreuer's colorspace.m (XYZ->Lab), D65 (0.950456, 1, 1.088754): not
// the white of the sRGB matrix, so that greys get a*, b* ~ 0.01-0.02, not 0.
constexpr double kWhite[3] = {0.950456, 1.0, 1.088754};
// colorspace.m's f(t): t^(1/3) unless t < 0.008856, then t 841/108 + 4/29 (also for negative t).
constexpr double kLabLinearBelow = 0.008856;

// LAB2LAB2000HL.m clips before its look-up: L* to [0, 100], a*, b* to [-128, 128].
constexpr double kLMax = 100, kAbLimit = 128;

// iCID.m iCID_Consts per intent and the exponents ([1 1 Alpha=3 1 1 1 1]; maps 6, 7 get 0 with
// Omit_Maps67).
constexpr std::array<double, 7> kConstsPerceptual = {0.002, 10, 10, 0.002, 0.002, 10, 10};
constexpr double kHueConstStronger = 0.02;     // c5 of hue-preserving and chromatic
constexpr double kChromaConstStronger = 0.02;  // c4 of chromatic
constexpr double kStructureExponent = 3;       // Options.Alpha

int thread_count(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

/// An image's three channels as doubles in [0, 1] (uint8 / 255, as iCID.m), row-major.
struct RgbPlanes {
  int rows = 0, cols = 0;
  std::array<std::vector<double>, 3> c;
};

RgbPlanes unit_planes(const RgbImage& image) {
  RgbPlanes p{image.height, image.width, {}};
  const std::size_t n = static_cast<std::size_t>(image.width) * image.height;
  for (int k = 0; k < 3; ++k) {
    p.c[k].resize(n);
    for (std::size_t i = 0; i < n; ++i) p.c[k][i] = image.rgb[3 * i + k] / 255.0;
  }
  return p;
}

int downsampling_factor(int rows, int cols) {
  return std::max(1, static_cast<int>(std::round(std::min(rows, cols) / kDownsamplingSide)));
}

/// imfilter's 'symmetric' border for an index within one image size of the edge.
int mirror(int i, int n) { return i < 0 ? -1 - i : (i >= n ? 2 * n - 1 - i : i); }

/// imfilter(img, ones(f)/f^2, 'symmetric', 'same') on the gamma-encoded values, then
/// img(1:f:end, 1:f:end): output pixel (r, s) averages input rows f r - (c - 1) .. f r + (f - c)
/// (and the same columns), c = floor((f + 1) / 2) MATLAB's kernel centre; ceil(M / f) rows.
RgbPlanes box_downsample(const RgbPlanes& in, int f) {
  const int centre = (f + 1) / 2;
  RgbPlanes out{(in.rows + f - 1) / f, (in.cols + f - 1) / f, {}};
  const double weight = 1.0 / (static_cast<double>(f) * f);
  for (int k = 0; k < 3; ++k) {
    out.c[k].resize(static_cast<std::size_t>(out.rows) * out.cols);
    for (int r = 0; r < out.rows; ++r) {
      for (int s = 0; s < out.cols; ++s) {
        double sum = 0;
        for (int dy = 1 - centre; dy <= f - centre; ++dy) {
          const std::size_t row = static_cast<std::size_t>(mirror(f * r + dy, in.rows)) * in.cols;
          for (int dx = 1 - centre; dx <= f - centre; ++dx) {
            sum += weight * in.c[k][row + mirror(f * s + dx, in.cols)];
          }
        }
        out.c[k][static_cast<std::size_t>(r) * out.cols + s] = sum;
      }
    }
  }
  return out;
}

/// colorspace.m's sRGB -> XYZ: the inverse of its rounded XYZ -> sRGB matrix (3.2406 ...), not
/// the 0.4124... matrix of qm3d's other metrics.
const Eigen::Matrix3d& rgb_to_xyz() {
  static const Eigen::Matrix3d m = [] {
    Eigen::Matrix3d xyz_to_rgb;
    xyz_to_rgb << 3.2406, -1.5372, -0.4986, -0.9689, 1.8758, 0.0415, 0.0557, -0.2040, 1.057;
    return Eigen::Matrix3d(xyz_to_rgb.inverse());
  }();
  return m;
}

/// The planes sized for rows x cols (kept, not cleared, when they already are).
void resize(XyzPlanes& p, int rows, int cols) {
  p.rows = rows;
  p.cols = cols;
  const std::size_t n = static_cast<std::size_t>(rows) * cols;
  for (auto* plane : {&p.x, &p.y, &p.z}) plane->resize(n);
}

/// Linearised (srgb_to_linear: colorspace.m's threshold 0.0404482362771076) and -> XYZ.
void to_xyz(const RgbPlanes& in, XyzPlanes& out) {
  const std::size_t n = in.c[0].size();
  resize(out, in.rows, in.cols);
  const Eigen::Matrix3d& m = rgb_to_xyz();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d rgb(srgb_to_linear(in.c[0][i]), srgb_to_linear(in.c[1][i]),
                              srgb_to_linear(in.c[2][i]));
    const Eigen::Vector3d xyz = m * rgb;
    out.x[i] = xyz[0];
    out.y[i] = xyz[1];
    out.z[i] = xyz[2];
  }
}

/// to_xyz of an image's 8-bit values themselves (no downsampling): each channel's
/// srgb_to_linear(k / 255.0) taken from a table of the 256 values that very call gives, so
/// the same bits as unit_planes then to_xyz without a call a channel.
void to_xyz(const RgbImage& image, XyzPlanes& out) {
  static const std::array<double, 256> linear = [] {
    std::array<double, 256> t{};
    for (int k = 0; k < 256; ++k) t[k] = srgb_to_linear(k / 255.0);
    return t;
  }();
  const std::size_t n = static_cast<std::size_t>(image.width) * image.height;
  resize(out, image.height, image.width);
  const Eigen::Matrix3d& m = rgb_to_xyz();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d rgb(linear[image.rgb[3 * i]], linear[image.rgb[3 * i + 1]],
                              linear[image.rgb[3 * i + 2]]);
    const Eigen::Vector3d xyz = m * rgb;
    out.x[i] = xyz[0];
    out.y[i] = xyz[1];
    out.z[i] = xyz[2];
  }
}

double lab_f(double t) {
  return t < kLabLinearBelow ? t * (841.0 / 108.0) + 4.0 / 29.0 : std::pow(t, 1.0 / 3.0);
}

/// An image in LAB2000HL: L and the chroma plane a, b.
struct Lab2000hlPlanes {
  std::vector<double> l, a, b;
};

/// XYZ -> CIELAB (white kWhite), clipped, -> LAB2000HL by the table (interp1 / interp2: linear
/// and bilinear, the rules of Lab2000hlTable::from_cielab on the clipped values).
void to_lab2000hl(const XyzPlanes& in, const Lab2000hlTable& table, Lab2000hlPlanes& out) {
  const std::size_t n = in.x.size();
  for (auto* plane : {&out.l, &out.a, &out.b}) plane->resize(n);
  // Both passes are pure functions of their pixel's values: a pixel equal to the one before
  // it (a rendered view's flat background, mostly) takes that pixel's results, the same bits.
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0 && in.x[i] == in.x[i - 1] && in.y[i] == in.y[i - 1] && in.z[i] == in.z[i - 1]) {
      out.l[i] = out.l[i - 1];
      out.a[i] = out.a[i - 1];
      out.b[i] = out.b[i - 1];
      continue;
    }
    const double fx = lab_f(in.x[i] / kWhite[0]);
    const double fy = lab_f(in.y[i] / kWhite[1]);
    const double fz = lab_f(in.z[i] / kWhite[2]);
    out.l[i] = std::clamp(116.0 * fy - 16.0, 0.0, kLMax);
    out.a[i] = std::clamp(500.0 * (fx - fy), -kAbLimit, kAbLimit);
    out.b[i] = std::clamp(200.0 * (fy - fz), -kAbLimit, kAbLimit);
  }
  // The look-ups in a pass of their own: the tables (1.8 MB) miss the cache, and a loop of
  // look-ups alone keeps many misses in flight.
  Lab before{std::nan(""), 0, 0}, after{};  // no pixel equals a NaN
  for (std::size_t i = 0; i < n; ++i) {
    const Lab lab{out.l[i], out.a[i], out.b[i]};
    if (!(lab.L == before.L && lab.a == before.a && lab.b == before.b)) {
      before = lab;
      after = table.from_cielab(lab);
    }
    out.l[i] = after.L;
    out.a[i] = after.a;
    out.b[i] = after.b;
  }
}

/// fspecial('gaussian', 11, 2): h(i, j) = exp(-(x^2 + y^2) / 8), x, y = -5..5, divided by
/// the sum of all 121 (summed column by column).
using Window = std::array<std::array<double, kWindowSize>, kWindowSize>;
const Window& window_weights() {
  static const Window h = [] {
    Window w{};
    double sum = 0;
    for (int j = 0; j < kWindowSize; ++j) {
      for (int i = 0; i < kWindowSize; ++i) {
        const double x = j - kWindowRadius, y = i - kWindowRadius;
        w[i][j] = std::exp(-(x * x + y * y) / (2 * kWindowSigma * kWindowSigma));
        sum += w[i][j];
      }
    }
    for (auto& row : w) {
      for (double& v : row) v /= sum;
    }
    return w;
  }();
  return h;
}

/// filter2(W, q, 'valid'): the window mean at each pixel at least 5 pixels from the edge. The
/// window's 121 products are added in the reference's order (Octave's conv2, 'valid'; W is
/// symmetric): kernel column j outer, row i inner, each adding W(i, j) q(r + 10 - i, c + 10 - j)
/// to the running sum. The order decides the last bits, which flat areas (variances
/// E[x^2] - mu^2 of ~0) turn into differences of ~1e-12 in the maps; a separable filter
/// differs there.
/// The output pixels of a row are summed kWindowVectors x 4 at a time in registers (the 121
/// steps of each pixel's sum in the order above), then 4 at a time, then one by one; GCC's
/// vector types keep the loads plain (left to itself it reversed each vector with a permute).
/// Compiled twice, for AVX2 and for the baseline, chosen at run time: the same additions and
/// multiplications in the same order (AVX2 without FMA), so the same bits, twice as fast.
typedef double Vec4 __attribute__((vector_size(32), aligned(8), may_alias));
constexpr int kVecWidth = 4;
// 8 accumulators: enough independent additions to hide the adder's latency.
constexpr int kWindowVectors = 8;

/// The window sums of kVectors x 4 consecutive output pixels, `in` at the first's window's
/// bottom-right input (kernel element i = j = 0).
template <int kVectors>
__attribute__((always_inline)) inline void window_vectors(const Window& h, const double* in,
                                                          int cols, double* o) {
  Vec4 acc[kVectors] = {};
  for (int j = 0; j < kWindowSize; ++j) {
    for (int i = 0; i < kWindowSize; ++i) {
      const double w = h[i][j];
      const Vec4* row =
          reinterpret_cast<const Vec4*>(in - static_cast<std::ptrdiff_t>(i) * cols - j);
      for (int v = 0; v < kVectors; ++v) acc[v] += w * row[v];
    }
  }
  Vec4* out = reinterpret_cast<Vec4*>(o);
  for (int v = 0; v < kVectors; ++v) out[v] = acc[v];
}

/// The same for one output pixel.
__attribute__((always_inline)) inline double window_one(const Window& h, const double* in,
                                                        int cols) {
  double acc = 0;
  for (int j = 0; j < kWindowSize; ++j) {
    for (int i = 0; i < kWindowSize; ++i)
      acc += h[i][j] * in[-static_cast<std::ptrdiff_t>(i) * cols - j];
  }
  return acc;
}

__attribute__((target_clones("avx2", "default"))) void window_mean(const std::vector<double>& q,
                                                                   int rows, int cols,
                                                                   std::vector<double>& out) {
  const Window& h = window_weights();
  const int out_rows = rows - 2 * kWindowRadius, out_cols = cols - 2 * kWindowRadius;
  out.resize(static_cast<std::size_t>(out_rows) * out_cols);
  constexpr int kWide = kWindowVectors * kVecWidth;
  for (int r = 0; r < out_rows; ++r) {
    double* o = &out[static_cast<std::size_t>(r) * out_cols];
    const double* in = &q[static_cast<std::size_t>(r + kWindowSize - 1) * cols + (kWindowSize - 1)];
    int c0 = 0;
    for (; c0 + kWide <= out_cols; c0 += kWide)
      window_vectors<kWindowVectors>(h, in + c0, cols, o + c0);
    for (; c0 + kVecWidth <= out_cols; c0 += kVecWidth) window_vectors<1>(h, in + c0, cols, o + c0);
    for (; c0 < out_cols; ++c0) o[c0] = window_one(h, in + c0, cols);
  }
}

/// The per-pixel quantities whose window means the maps use (iCID.m's premaps).
enum Quantity { kL1, kL2, kC1, kC2, kL1Sq, kL2Sq, kC1Sq, kC2Sq, kL12, kC12, kHue, kQuantities };

using Planes = std::vector<double>;

void quantities(const Lab2000hlPlanes& p1, const Lab2000hlPlanes& p2,
                std::array<Planes, kQuantities>& q) {
  const std::size_t n = p1.l.size();
  for (auto& v : q) v.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double c1_sq = p1.a[i] * p1.a[i] + p1.b[i] * p1.b[i];
    const double c2_sq = p2.a[i] * p2.a[i] + p2.b[i] * p2.b[i];
    const double c1 = std::sqrt(c1_sq), c2 = std::sqrt(c2_sq);
    const double da = p1.a[i] - p2.a[i], db = p1.b[i] - p2.b[i], dc = c1 - c2;
    q[kL1][i] = p1.l[i];
    q[kL2][i] = p2.l[i];
    q[kC1][i] = c1;
    q[kC2][i] = c2;
    q[kL1Sq][i] = p1.l[i] * p1.l[i];
    q[kL2Sq][i] = p2.l[i] * p2.l[i];
    q[kC1Sq][i] = c1_sq;  // A^2 + B^2 itself, not C^2 (iCID.m C1_sq)
    q[kC2Sq][i] = c2_sq;
    q[kL12][i] = p1.l[i] * p2.l[i];
    q[kC12][i] = c1 * c2;
    // The hue difference: the square root per pixel, before the window mean (whose square is
    // dH^2). Its argument can be -1e-15 by rounding, where MATLAB takes a complex root whose
    // contribution to the real result is ~1e-30: 0 here.
    q[kHue][i] = std::sqrt(std::max(0.0, da * da + db * db - dc * dc));
  }
}

/// The seven inv_k of one pixel from the window means m[q] (iCID.m's Maps_inv).
std::array<double, 7> inverse_maps(const std::array<double, kQuantities>& m,
                                   const std::array<double, 7>& c) {
  // Variances clipped at 0 (E[x^2] - mu^2 can be slightly negative); covariances not.
  const double sl1_sq = std::max(0.0, m[kL1Sq] - m[kL1] * m[kL1]);
  const double sl2_sq = std::max(0.0, m[kL2Sq] - m[kL2] * m[kL2]);
  const double sc1_sq = std::max(0.0, m[kC1Sq] - m[kC1] * m[kC1]);
  const double sc2_sq = std::max(0.0, m[kC2Sq] - m[kC2] * m[kC2]);
  const double sl1 = std::sqrt(sl1_sq), sl2 = std::sqrt(sl2_sq);
  const double sc1 = std::sqrt(sc1_sq), sc2 = std::sqrt(sc2_sq);
  const double dl_sq = (m[kL1] - m[kL2]) * (m[kL1] - m[kL2]);
  const double dc_sq = (m[kC1] - m[kC2]) * (m[kC1] - m[kC2]);
  const double dh_sq = m[kHue] * m[kHue];
  const double sl12 = m[kL12] - m[kL1] * m[kL2];
  const double sc12 = m[kC12] - m[kC1] * m[kC2];
  return {1.0 / (c[0] * dl_sq + 1.0),
          (c[1] + 2.0 * sl1 * sl2) / (c[1] + sl1_sq + sl2_sq),
          (c[2] + std::abs(sl12)) / (c[2] + sl1 * sl2),
          1.0 / (c[3] * dc_sq + 1.0),
          1.0 / (c[4] * dh_sq + 1.0),
          (c[5] + 2.0 * sc1 * sc2) / (c[5] + sc1_sq + sc2_sq),
          (c[6] + std::abs(sc12)) / (c[6] + sc1 * sc2)};
}

/// The planes of a call (XYZ, LAB2000HL and the maps': 42 of the image's size), kept by each
/// calling thread between calls for images up to kScratchPixels: fresh pages cost ~20 % of a
/// 256^2 pair without the appearance model (page faults, zeroing). Larger images use planes of
/// their own, freed after the call.
struct MapScratch {
  XyzPlanes xyz_a, xyz_b;
  Lab2000hlPlanes lab_a, lab_b;
  std::array<Planes, kQuantities> quantities, means;
  std::array<Planes, 8> terms;
};
constexpr std::size_t kScratchPixels = std::size_t{1} << 19;

MapScratch& map_scratch() {
  static thread_local MapScratch scratch;
  return scratch;
}

std::array<double, 7> intent_constants(IcidIntent intent) {
  std::array<double, 7> c = kConstsPerceptual;
  if (intent != IcidIntent::kPerceptual) c[4] = kHueConstStronger;
  if (intent == IcidIntent::kChromatic) c[3] = kChromaConstStronger;
  return c;
}

std::array<double, 7> exponents(bool omit_maps67) {
  return {1, 1, kStructureExponent, 1, 1, omit_maps67 ? 0.0 : 1.0, omit_maps67 ? 0.0 : 1.0};
}

/// The maps' means and the prediction: mean2 of the reference = sum(x(:)) / numel(x), x(:) in
/// column-major order added one by one (Octave's sum). The per-pixel terms are computed first
/// (rows in parallel), then summed in that order: the same bits for any thread count, and the
/// reference's rounding of a mean whose terms are ~1 (1 - mean of products ~1 - 3e-4 loses 4
/// digits: a row-major sum differs from it by up to ~4e-10 relative there).
IcidResult pool_maps(const std::array<Planes, kQuantities>& means, int rows, int cols,
                     const IcidOptions& o, std::array<Planes, 8>& terms) {
  const std::array<double, 7> c = intent_constants(o.intent), e = exponents(o.omit_maps67);
  const std::size_t n = static_cast<std::size_t>(rows) * cols;
  for (auto& t : terms) t.resize(n);  // 1 - inv_k (k < 7), the product of inv_k^e_k
#pragma omp parallel for schedule(static) num_threads(thread_count(o.threads))
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * cols + x;
      std::array<double, kQuantities> m;
      for (int q = 0; q < kQuantities; ++q) m[q] = means[q][i];
      const std::array<double, 7> inv = inverse_maps(m, c);
      double product = 1;
      for (int k = 0; k < 7; ++k) {
        terms[k][i] = 1.0 - inv[k];
        product *= e[k] == 1 ? inv[k] : std::pow(inv[k], e[k]);
      }
      terms[7][i] = product;
    }
  }
  std::array<double, 8> total{};
  for (int x = 0; x < cols; ++x) {
    for (int y = 0; y < rows; ++y) {
      const std::size_t i = static_cast<std::size_t>(y) * cols + x;
      for (int k = 0; k < 8; ++k) total[k] += terms[k][i];
    }
  }
  IcidResult r;
  r.map_width = cols;
  r.map_height = rows;
  if (o.keep_map) {
    r.map.resize(n);
    for (std::size_t i = 0; i < n; ++i) r.map[i] = 1.0 - terms[7][i];
  }
  const double count = static_cast<double>(n);
  for (int k = 0; k < 7; ++k) r.maps[k] = total[k] / count;
  r.icid = 1.0 - total[7] / count;
  return r;
}

}  // namespace

IcidIntent icid_intent(const std::string& name) {
  if (name == "perceptual") return IcidIntent::kPerceptual;
  if (name == "hue-preserving") return IcidIntent::kHuePreserving;
  if (name == "chromatic") return IcidIntent::kChromatic;
  throw std::invalid_argument("intent: '" + name +
                              "' is not one of perceptual, hue-preserving, chromatic");
}

const std::array<std::string, 7>& icid_map_names() {
  static const std::array<std::string, 7> names = {"icid_m1", "icid_m2", "icid_m3", "icid_m4",
                                                   "icid_m5", "icid_m6", "icid_m7"};
  return names;
}

std::filesystem::path icid_table_dir(const std::filesystem::path& data_dir) {
  return resolve_data_dir(data_dir) / "icid";
}

IcidResult icid(const RgbImage& a, const RgbImage& b, const Lab2000hlTable& table,
                const IcidOptions& options) {
  for (const RgbImage* image : {&a, &b}) {
    if (image->width <= 0 || image->height <= 0 ||
        image->rgb.size() != static_cast<std::size_t>(image->width) * image->height * 3) {
      throw std::invalid_argument("icid: an image of " + std::to_string(image->width) + "x" +
                                  std::to_string(image->height) + " pixels holds " +
                                  std::to_string(image->rgb.size()) + " bytes, not 3 a pixel");
    }
  }
  if (a.width != b.width || a.height != b.height) {
    throw std::invalid_argument("icid: the images differ in size (" + std::to_string(a.width) +
                                "x" + std::to_string(a.height) + " and " + std::to_string(b.width) +
                                "x" + std::to_string(b.height) + ")");
  }
  const int f = options.downsampling ? downsampling_factor(a.height, a.width) : 1;
  const int rows = (a.height + f - 1) / f, cols = (a.width + f - 1) / f;  // box_downsample's
  if (rows < kWindowSize || cols < kWindowSize) {
    throw std::invalid_argument("icid: images of " + std::to_string(cols) + "x" +
                                std::to_string(rows) +
                                " pixels (after downsampling); at least 11x11 needed");
  }
  MapScratch local;
  MapScratch& m = static_cast<std::size_t>(rows) * cols <= kScratchPixels ? map_scratch() : local;
  XyzPlanes &xa = m.xyz_a, &xb = m.xyz_b;
  if (f > 1) {
    to_xyz(box_downsample(unit_planes(a), f), xa);
    to_xyz(box_downsample(unit_planes(b), f), xb);
  } else {
    to_xyz(a, xa);
    to_xyz(b, xb);
  }
  if (options.iam) icid_detail::csf_filter(xa, xb, options.threads);
  to_lab2000hl(xa, table, m.lab_a);
  to_lab2000hl(xb, table, m.lab_b);
  quantities(m.lab_a, m.lab_b, m.quantities);
#pragma omp parallel for schedule(dynamic, 1) num_threads(thread_count(options.threads))
  for (int k = 0; k < kQuantities; ++k) window_mean(m.quantities[k], rows, cols, m.means[k]);
  return pool_maps(m.means, rows - 2 * kWindowRadius, cols - 2 * kWindowRadius, options, m.terms);
}

}  // namespace qm3d::render
