#include "pca_normals.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "kd_tree.h"
#include "qm3d/common/error.h"

namespace qm3d::pointcloud::detail {
namespace {

// ---- LAPACK's dsyevd('V', 'L') for n = 3, routine by routine ------------------------------
// Reference-LAPACK 3.11 and netlib BLAS (the libraries numpy.linalg.eigh calls on Debian 12).
// Each helper is the routine named, specialised to the sizes a 3x3 matrix gives; the order of
// every floating-point operation, the zero tests and the signed zeros are LAPACK's.

using Mat3 = std::array<std::array<double, 3>, 3>;  // m[row][col]

constexpr double kEps = std::numeric_limits<double>::epsilon() * 0.5;  // dlamch('E')
constexpr double kSafeMin = std::numeric_limits<double>::min();        // dlamch('S')

// dlapy2: sqrt(x² + y²) without destructive underflow or overflow.
double lapy2(double x, double y) {
  if (std::isnan(x)) return x;
  if (std::isnan(y)) return y;
  const double w = std::max(std::fabs(x), std::fabs(y));
  const double z = std::min(std::fabs(x), std::fabs(y));
  if (z == 0 || w > std::numeric_limits<double>::max()) return w;
  const double ratio = z / w;
  return w * std::sqrt(1.0 + ratio * ratio);
}

// dlartg (la_xlartg, LAPACK >= 3.10): the plane rotation [c s; -s c] [f; g] = [r; 0].
void lartg(double f, double g, double& c, double& s, double& r) {
  const double safmax = 1.0 / kSafeMin;
  const double rtmin = std::sqrt(kSafeMin);
  const double rtmax = std::sqrt(safmax / 2);
  const double f1 = std::fabs(f);
  const double g1 = std::fabs(g);
  if (g == 0) {
    c = 1;
    s = 0;
    r = f;
  } else if (f == 0) {
    c = 0;
    s = std::copysign(1.0, g);
    r = g1;
  } else if (f1 > rtmin && f1 < rtmax && g1 > rtmin && g1 < rtmax) {
    const double d = std::sqrt(f * f + g * g);
    c = f1 / d;
    r = std::copysign(d, f);
    s = g / r;
  } else {
    const double u = std::min(safmax, std::max({kSafeMin, f1, g1}));
    const double fs = f / u;
    const double gs = g / u;
    const double d = std::sqrt(fs * fs + gs * gs);
    c = std::fabs(fs) / d;
    r = std::copysign(d, f);
    s = gs / r;
    r = r * u;
  }
}

// dlaev2: eigen-decomposition of [a b; b c]: rt1 (larger |.|), rt2, and (cs1, sn1) the unit
// eigenvector of rt1.
void laev2(double a, double b, double c, double& rt1, double& rt2, double& cs1, double& sn1) {
  const double sm = a + c;
  const double df = a - c;
  const double adf = std::fabs(df);
  const double tb = b + b;
  const double ab = std::fabs(tb);
  const double acmx = std::fabs(a) > std::fabs(c) ? a : c;
  const double acmn = std::fabs(a) > std::fabs(c) ? c : a;
  double rt = 0;
  if (adf > ab) {
    const double q = ab / adf;
    rt = adf * std::sqrt(1.0 + q * q);
  } else if (adf < ab) {
    const double q = adf / ab;
    rt = ab * std::sqrt(1.0 + q * q);
  } else {
    rt = ab * std::sqrt(2.0);
  }
  int sgn1 = 1;
  if (sm < 0) {
    rt1 = 0.5 * (sm - rt);
    sgn1 = -1;
    rt2 = (acmx / rt1) * acmn - (b / rt1) * b;
  } else if (sm > 0) {
    rt1 = 0.5 * (sm + rt);
    rt2 = (acmx / rt1) * acmn - (b / rt1) * b;
  } else {
    rt1 = 0.5 * rt;
    rt2 = -0.5 * rt;
  }
  const int sgn2 = df >= 0 ? 1 : -1;
  const double cs = df >= 0 ? df + rt : df - rt;
  if (std::fabs(cs) > ab) {
    const double ct = -tb / cs;
    sn1 = 1.0 / std::sqrt(1.0 + ct * ct);
    cs1 = ct * sn1;
  } else if (ab == 0) {
    cs1 = 1;
    sn1 = 0;
  } else {
    const double tn = -cs / tb;
    cs1 = 1.0 / std::sqrt(1.0 + tn * tn);
    sn1 = tn * cs1;
  }
  if (sgn1 == sgn2) {
    const double tn = cs1;
    cs1 = -sn1;
    sn1 = tn;
  }
}

// dlasr('R', 'V', 'F' or 'B'): z := z P, P the product of the rotations (c[j], s[j]) in the
// planes (first + j, first + j + 1), j ascending (forward) or descending.
void lasr_right(Mat3& z, int first, int count, const double* c, const double* s, bool forward) {
  for (int step = 0; step < count - 1; ++step) {
    const int j = forward ? step : count - 2 - step;
    const double ct = c[j];
    const double st = s[j];
    if (ct == 1 && st == 0) continue;
    for (int i = 0; i < 3; ++i) {
      const double temp = z[i][first + j + 1];
      z[i][first + j + 1] = ct * temp - st * z[i][first + j];
      z[i][first + j] = st * temp + ct * z[i][first + j];
    }
  }
}

// One block [l, lend] of dsteqr's QL iteration (|d[lend]| >= |d[l]|). Returns false when the
// iteration budget (30 n) ran out.
bool ql_block(std::array<double, 3>& d, std::array<double, 2>& e, Mat3& z, int l, int lend,
              int& jtot) {
  const double eps2 = kEps * kEps;
  std::array<double, 2> work_c{}, work_s{};
  while (true) {
    int m = lend;
    for (int mm = l; mm < lend; ++mm) {
      const double tst = std::fabs(e[mm]) * std::fabs(e[mm]);
      if (tst <= (eps2 * std::fabs(d[mm])) * std::fabs(d[mm + 1]) + kSafeMin) {
        m = mm;
        break;
      }
    }
    if (m < lend) e[m] = 0;
    double p = d[l];
    if (m == l) {  // eigenvalue found
      d[l] = p;
      if (++l <= lend) continue;
      return true;
    }
    if (m == l + 1) {
      double rt1 = 0, rt2 = 0, c = 0, s = 0;
      laev2(d[l], e[l], d[l + 1], rt1, rt2, c, s);
      lasr_right(z, l, 2, &c, &s, false);
      d[l] = rt1;
      d[l + 1] = rt2;
      e[l] = 0;
      l += 2;
      if (l <= lend) continue;
      return true;
    }
    if (jtot == 90) return false;
    ++jtot;
    double g = (d[l + 1] - p) / (2.0 * e[l]);
    double r = lapy2(g, 1.0);
    g = d[m] - p + (e[l] / (g + std::copysign(r, g)));
    double s = 1, c = 1;
    p = 0;
    for (int i = m - 1; i >= l; --i) {
      const double f = s * e[i];
      const double b = c * e[i];
      lartg(g, f, c, s, r);
      if (i != m - 1) e[i + 1] = r;
      g = d[i + 1] - p;
      r = (d[i] - g) * s + 2.0 * c * b;
      p = s * r;
      d[i + 1] = g + p;
      g = c * r - b;
      work_c[i] = c;
      work_s[i] = -s;
    }
    lasr_right(z, l, m - l + 1, &work_c[l], &work_s[l], false);
    d[l] = d[l] - p;
    e[l] = g;
  }
}

// One block [lend, l] of dsteqr's QR iteration (|d[lend]| < |d[l]|, lend < l).
bool qr_block(std::array<double, 3>& d, std::array<double, 2>& e, Mat3& z, int l, int lend,
              int& jtot) {
  const double eps2 = kEps * kEps;
  std::array<double, 2> work_c{}, work_s{};
  while (true) {
    int m = lend;
    for (int mm = l; mm > lend; --mm) {
      const double tst = std::fabs(e[mm - 1]) * std::fabs(e[mm - 1]);
      if (tst <= (eps2 * std::fabs(d[mm])) * std::fabs(d[mm - 1]) + kSafeMin) {
        m = mm;
        break;
      }
    }
    if (m > lend) e[m - 1] = 0;
    double p = d[l];
    if (m == l) {  // eigenvalue found
      d[l] = p;
      if (--l >= lend) continue;
      return true;
    }
    if (m == l - 1) {
      double rt1 = 0, rt2 = 0, c = 0, s = 0;
      laev2(d[l - 1], e[l - 1], d[l], rt1, rt2, c, s);
      lasr_right(z, l - 1, 2, &c, &s, true);
      d[l - 1] = rt1;
      d[l] = rt2;
      e[l - 1] = 0;
      l -= 2;
      if (l >= lend) continue;
      return true;
    }
    if (jtot == 90) return false;
    ++jtot;
    double g = (d[l - 1] - p) / (2.0 * e[l - 1]);
    double r = lapy2(g, 1.0);
    g = d[m] - p + (e[l - 1] / (g + std::copysign(r, g)));
    double s = 1, c = 1;
    p = 0;
    for (int i = m; i <= l - 1; ++i) {
      const double f = s * e[i];
      const double b = c * e[i];
      lartg(g, f, c, s, r);
      if (i != m) e[i - 1] = r;
      g = d[i] - p;
      r = (d[i + 1] - g) * s + 2.0 * c * b;
      p = s * r;
      d[i] = g + p;
      g = c * r - b;
      work_c[i] = c;
      work_s[i] = s;
    }
    lasr_right(z, m, l - m + 1, &work_c[m], &work_s[m], true);
    d[l] = d[l] - p;
    e[l - 1] = g;
  }
}

// dsteqr('I', 3, d, e, z): eigenvalues and eigenvectors of the symmetric tridiagonal matrix
// (d, e), z starting from the identity. The splitting, the choice between QL and QR per block
// and the final selection sort are dsteqr's. False when it did not converge. (Its rescaling of
// blocks whose largest entry is above ~1e153 or below ~1e-123 is left out: see the \bug in the
// header.)
bool steqr(std::array<double, 3>& d, std::array<double, 2>& e, Mat3& z) {
  z = Mat3{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  int jtot = 0;
  int l1 = 0;
  while (l1 < 3) {
    if (l1 > 0) e[l1 - 1] = 0;
    int m = 2;
    for (int mm = l1; mm < 2; ++mm) {
      const double tst = std::fabs(e[mm]);
      if (tst == 0) {
        m = mm;
        break;
      }
      if (tst <= (std::sqrt(std::fabs(d[mm])) * std::sqrt(std::fabs(d[mm + 1]))) * kEps) {
        e[mm] = 0;
        m = mm;
        break;
      }
    }
    int l = l1;
    int lend = m;
    l1 = m + 1;
    if (lend == l) continue;
    double anorm = std::fabs(d[lend]);  // dlanst('M') of the block
    for (int i = l; i < lend; ++i) anorm = std::max({anorm, std::fabs(d[i]), std::fabs(e[i])});
    if (anorm == 0) continue;
    if (std::fabs(d[lend]) < std::fabs(d[l])) std::swap(l, lend);
    const bool converged =
        lend > l ? ql_block(d, e, z, l, lend, jtot) : qr_block(d, e, z, l, lend, jtot);
    if (!converged) return false;  // dsteqr's INFO > 0
  }
  for (int i = 0; i < 2; ++i) {  // selection sort, swapping eigenvector columns
    int k = i;
    double p = d[i];
    for (int j = i + 1; j < 3; ++j) {
      if (d[j] < p) {
        k = j;
        p = d[j];
      }
    }
    if (k != i) {
      d[k] = d[i];
      d[i] = p;
      for (int row = 0; row < 3; ++row) std::swap(z[row][i], z[row][k]);
    }
  }
  return true;
}

// dlarfg(2, alpha, x): the reflector H = I - tau v vᵀ, v = (1, x'), with H (alpha, x) = (beta, 0).
double larfg2(double& alpha, double& x) {
  const double xnorm = std::fabs(x);  // dnrm2 of one element
  if (xnorm == 0) return 0;
  const double beta = -std::copysign(lapy2(alpha, xnorm), alpha);
  const double tau = (beta - alpha) / beta;
  x = (1.0 / (alpha - beta)) * x;
  alpha = beta;
  return tau;
}

// dsytd2('L') for n = 3: a := Qᵀ a Q tridiagonal (d, e); returns tau, the reflector's vector
// (1, a[2][0]) stays in a.
double sytd2_lower(Mat3& a, std::array<double, 3>& d, std::array<double, 2>& e) {
  const double tau = larfg2(a[1][0], a[2][0]);
  e[0] = a[1][0];
  if (tau != 0) {
    a[1][0] = 1;
    const std::array<double, 2> v{a[1][0], a[2][0]};
    std::array<double, 2> w{0, 0};  // dsymv('L', 2, tau, a[1..2][1..2], v, 0, w)
    double temp1 = tau * v[0];
    double temp2 = 0;
    w[0] = w[0] + temp1 * a[1][1];
    w[1] = w[1] + temp1 * a[2][1];
    temp2 = temp2 + a[2][1] * v[1];
    w[0] = w[0] + tau * temp2;
    temp1 = tau * v[1];
    w[1] = w[1] + temp1 * a[2][2];
    w[1] = w[1] + tau * 0.0;
    double dot = 0;  // ddot(2, w, v)
    dot = dot + w[0] * v[0];
    dot = dot + w[1] * v[1];
    const double alpha = -(0.5 * tau * dot);
    if (alpha != 0) {  // daxpy
      w[0] = w[0] + alpha * v[0];
      w[1] = w[1] + alpha * v[1];
    }
    // dsyr2('L', 2, -1, v, w, a[1..2][1..2])
    if (v[0] != 0 || w[0] != 0) {
      const double t1 = -1.0 * w[0];
      const double t2 = -1.0 * v[0];
      a[1][1] = a[1][1] + v[0] * t1 + w[0] * t2;
      a[2][1] = a[2][1] + v[1] * t1 + w[1] * t2;
    }
    if (v[1] != 0 || w[1] != 0) {
      const double t1 = -1.0 * w[1];
      const double t2 = -1.0 * v[1];
      a[2][2] = a[2][2] + v[1] * t1 + w[1] * t2;
    }
    a[1][0] = e[0];
  }
  d[0] = a[0][0];
  e[1] = a[2][1];  // the second reflector (dlarfg of one element) is the identity
  d[1] = a[1][1];
  d[2] = a[2][2];
  return tau;
}

// dorm2r through dormtr('L', 'L', 'N'): z := Q z, applying the reflector (tau, v = (1, v1)) to
// rows 1..2 of z with dlarf's trimming of trailing zero rows and columns.
void apply_reflector(Mat3& z, double tau, double v1) {
  if (tau == 0) return;
  const std::array<double, 2> v{1.0, v1};
  const int rows = v1 != 0 ? 2 : 1;  // dlarf's lastv
  int cols = 0;                      // iladlc(rows, 3, z[1..rows][.])
  if (z[1][2] != 0 || z[rows][2] != 0) {
    cols = 3;
  } else {
    for (int col = 2; col >= 0 && cols == 0; --col) {
      for (int i = 0; i < rows; ++i) {
        if (z[1 + i][col] != 0) {
          cols = col + 1;
          break;
        }
      }
    }
  }
  std::array<double, 3> work{0, 0, 0};  // dgemv('T'): work = z[1..rows][..cols]ᵀ v
  for (int j = 0; j < cols; ++j) {
    double temp = 0;
    for (int i = 0; i < rows; ++i) temp = temp + z[1 + i][j] * v[i];
    work[j] = work[j] + temp;
  }
  for (int j = 0; j < cols; ++j) {  // dger: z -= tau v workᵀ
    if (work[j] == 0) continue;
    const double temp = -tau * work[j];
    for (int i = 0; i < rows; ++i) z[1 + i][j] = z[1 + i][j] + v[i] * temp;
  }
}

// ---- add_pca_normals.py --------------------------------------------------------------------

using Neighbourhood = std::array<std::uint32_t, kPcaNeighbours>;

// The 12 nearest points of `query` (itself included) in the tool's order: by squared distance,
// then by input index. The tree's kNN keeps the first of equal distances it meets, so when the
// 13th nearest ties the 12th, every point at most the 12th distance away is gathered (ties at
// the boundary included); either set is then ordered as the tool's partition + lexsort.
Neighbourhood nearest_points(const KdTree& tree, const std::vector<Vec3>& positions,
                             const Vec3& query, std::vector<Neighbour>& scratch) {
  constexpr std::size_t k = kPcaNeighbours;
  tree.knn_search(query, k + 1, scratch);
  if (scratch.size() > k && scratch[k].distance2 > scratch[k - 1].distance2) {
    scratch.resize(k);
  } else {
    const double kth_distance2 = scratch[k - 1].distance2;
    tree.radius_search(
        query, std::nextafter(kth_distance2, std::numeric_limits<double>::infinity()), scratch);
  }
  for (Neighbour& n : scratch) {
    n.index = tree.input_index()[n.index];
    n.distance2 = squared_distance(query, positions[n.index]);
  }
  std::sort(scratch.begin(), scratch.end(), [](const Neighbour& a, const Neighbour& b) {
    return a.distance2 != b.distance2 ? a.distance2 < b.distance2 : a.index < b.index;
  });
  Neighbourhood out{};
  for (int i = 0; i < kPcaNeighbours; ++i) out[i] = scratch[i].index;
  return out;
}

// (1/k) Σ (q − m)(q − m)ᵀ, m = (Σ q) / k: numpy's mean and einsum, summed in neighbour order.
Mat3 covariance(const std::vector<Vec3>& positions, const Neighbourhood& neighbours) {
  Vec3 mean{0, 0, 0};
  for (std::uint32_t index : neighbours)
    for (int c = 0; c < 3; ++c) mean[c] += positions[index][c];
  for (int c = 0; c < 3; ++c) mean[c] /= kPcaNeighbours;
  Mat3 cov{};
  for (std::uint32_t index : neighbours) {
    Vec3 q{};
    for (int c = 0; c < 3; ++c) q[c] = positions[index][c] - mean[c];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) cov[r][c] += q[r] * q[c];
  }
  for (auto& row : cov)
    for (double& value : row) value /= kPcaNeighbours;
  return cov;
}

// Sequential mean of all points (numpy's mean over axis 0 of an (n, 3) array).
Vec3 centroid(const std::vector<Vec3>& positions) {
  Vec3 sum{0, 0, 0};
  for (const Vec3& p : positions)
    for (int c = 0; c < 3; ++c) sum[c] += p[c];
  for (int c = 0; c < 3; ++c) sum[c] /= static_cast<double>(positions.size());
  return sum;
}

std::array<float, 3> oriented_normal(const Vec3& normal, const Vec3& point, const Vec3& center) {
  Vec3 offset{};
  for (int c = 0; c < 3; ++c) offset[c] = point[c] - center[c];
  // numpy's einsum('ij,ij->i') over 3 components: two SIMD lanes, (n0 d0 + n2 d2) + n1 d1.
  const double dot = (normal[0] * offset[0] + normal[2] * offset[2]) + normal[1] * offset[1];
  std::array<float, 3> out{};  // nrm[flip] *= -1 (0 becomes -0), then float32
  for (int c = 0; c < 3; ++c) out[c] = static_cast<float>(dot < 0 ? normal[c] * -1.0 : normal[c]);
  return out;
}

}  // namespace

SymmetricEigen3 symmetric_eigenvectors_3x3(const std::array<Vec3, 3>& matrix) {
  Mat3 a{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c <= r; ++c) a[r][c] = matrix[r][c];  // UPLO = 'L'
  std::array<double, 3> d{};
  std::array<double, 2> e{};
  const double tau = sytd2_lower(a, d, e);
  Mat3 z{};
  if (!steqr(d, e, z))  // numpy raises LinAlgError there
    throw NumericError(
        "PCA normals: the eigenvalues of a neighbourhood covariance did not converge");
  apply_reflector(z, tau, a[2][0]);
  SymmetricEigen3 out;
  for (int i = 0; i < 3; ++i) {
    out.values[i] = d[i];
    for (int r = 0; r < 3; ++r) out.vectors[i][r] = z[r][i];
  }
  return out;
}

std::vector<std::array<float, 3>> estimate_pca_normals(const std::vector<Vec3>& positions,
                                                       int threads) {
  if (positions.size() < static_cast<std::size_t>(kPcaNeighbours))
    throw NumericError("PCA normals need at least " + std::to_string(kPcaNeighbours) +
                       " points, the cloud has " + std::to_string(positions.size()));
  const KdTree tree(positions, threads);
  const Vec3 center = centroid(positions);
  std::vector<std::array<float, 3>> normals(positions.size());
  const auto count = static_cast<std::int64_t>(positions.size());
#pragma omp parallel num_threads(threads > 0 ? threads : omp_get_max_threads())
  {
    std::vector<Neighbour> scratch;
#pragma omp for schedule(static)
    for (std::int64_t i = 0; i < count; ++i) {
      const Neighbourhood neighbours = nearest_points(tree, positions, positions[i], scratch);
      const Mat3 cov = covariance(positions, neighbours);
      const SymmetricEigen3 eigen = symmetric_eigenvectors_3x3({cov[0], cov[1], cov[2]});
      normals[i] = oriented_normal(eigen.vectors[0], positions[i], center);
    }
  }
  return normals;
}

}  // namespace qm3d::pointcloud::detail
