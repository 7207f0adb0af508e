#include "quadric_fit.h"

#include <cmath>

namespace qm3d::pointcloud::detail {
namespace {

/// A fit counts as underdetermined below this scaled pivot ratio: its least-squares solution is
/// then sensitive to rounding beyond 1e-9 relative (about 1e-16 / ratio), so the QR
/// implementation's rounding shows in the result.
constexpr double kConditionLimit = 1e-7;

/// The fast path's limits (QuadricFitter):
/// * the design with unit columns has its smallest singular value at least kFastSingularBound
///   (1e5 times the underdetermined limit). Every scaled pivot of a column-pivoted QR is at least
///   that singular value, so no fit the fast path takes is one the reference's QR would call
///   underdetermined; and its condition number is at most about 250, so another rounding of the
///   least-squares solution moves it by about 1e-14 relative (1e-4 gave per-point differences
///   up to 1e-9 from the reference's on voxelised clouds);
/// * the normal's eigenvalue separated from the middle one by at least kFastEigenGap of the
///   largest (a normal determined to about 1e-13; its sign and the tangents' do not matter: |H|
///   and the foot point p + f n are invariant under them).
constexpr double kFastSingularBound = 1e-2;
constexpr double kFastEigenGap = 1e-3;
/// ... and the points not coplanar to rounding: the normal's eigenvalue at least kFastFlatness of
/// the largest (heights at least about 1e-4 of the neighbourhood's extent). On a plane (voxelised
/// clouds) the heights, and so the curvature, are rounding residues that another rounding of the
/// fit would change wholesale: there the reference's arithmetic decides.
constexpr double kFastFlatness = 1e-8;

/// Whether every pivot of the column-pivoted QR of `design` is at least kConditionLimit of its
/// column's norm: the diagonal of R for the design with unit columns, an estimate of the
/// reciprocal condition number that ignores the columns' scales (x^2, x, 1 differ by orders of
/// magnitude on small neighbourhoods without making the fit ill-posed).
///
/// |R(0,0)| is the largest column norm (the first pivot), so a pivot above kConditionLimit of it
/// (with a margin for the rounding of the two norms) passes without computing its column's norm:
/// on well-posed fits, which are nearly all, no norm is computed at all.
bool well_conditioned(const Eigen::ColPivHouseholderQR<Eigen::MatrixXd>& qr,
                      const Eigen::MatrixXd& design) {
  const auto& r = qr.matrixQR();
  const auto& perm = qr.colsPermutation().indices();
  const double sufficient = kConditionLimit * std::abs(r(0, 0)) * (1 + 1e-12);
  for (Eigen::Index i = 0; i < 6; ++i) {
    const double pivot = std::abs(r(i, i));
    if (pivot >= sufficient) continue;
    if (!(pivot >= kConditionLimit * design.col(perm(i)).norm())) return false;
  }
  return true;
}

// The neighbours' covariance as E[x x^T] - mu mu^T. Each entry is summed in neighbour order
// exactly as the reference's `M = M + neighbor * neighbor.transpose()` does, but in registers.
Eigen::Matrix3d covariance(const std::vector<Vec3>& points,
                           const std::vector<Neighbour>& neighbours) {
  double sx = 0, sy = 0, sz = 0;
  double sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
  for (const Neighbour& nb : neighbours) {
    const Vec3& p = points[nb.index];
    sx = sx + p[0];
    sy = sy + p[1];
    sz = sz + p[2];
    sxx = sxx + p[0] * p[0];
    sxy = sxy + p[0] * p[1];
    sxz = sxz + p[0] * p[2];
    syy = syy + p[1] * p[1];
    syz = syz + p[1] * p[2];
    szz = szz + p[2] * p[2];
  }
  const double count = static_cast<double>(neighbours.size());
  const Eigen::Vector3d mean(sx / count, sy / count, sz / count);
  const double inv = 1. / count;
  Eigen::Matrix3d moment;
  moment << inv * sxx - mean(0) * mean(0), inv * sxy - mean(0) * mean(1),
      inv * sxz - mean(0) * mean(2),  //
      inv * sxy - mean(1) * mean(0), inv * syy - mean(1) * mean(1), inv * syz - mean(1) * mean(2),
      inv * sxz - mean(2) * mean(0), inv * syz - mean(2) * mean(1), inv * szz - mean(2) * mean(2);
  return moment;
}

// A lower bound of the smallest singular value of R D^-1 (R upper triangular, D the design's
// column norms), i.e. of the design with unit columns: 1 / ||(R D^-1)^-1||_F.
double smallest_singular_value_bound(const double r[6][7], const double norm0[6]) {
  double u[6][6];
  for (int i = 0; i < 6; ++i) {
    for (int j = i; j < 6; ++j) u[i][j] = r[i][j] / norm0[j];
  }
  double inv[6][6];
  double frobenius2 = 0;
  for (int j = 0; j < 6; ++j) {
    inv[j][j] = 1 / u[j][j];
    frobenius2 += inv[j][j] * inv[j][j];
    for (int i = j - 1; i >= 0; --i) {
      double sum = 0;
      for (int k = i + 1; k <= j; ++k) sum += u[i][k] * inv[k][j];
      inv[i][j] = -sum / u[i][i];
      frobenius2 += inv[i][j] * inv[i][j];
    }
  }
  return 1 / std::sqrt(frobenius2);
}

}  // namespace

namespace {

// One Householder step of solve_well_posed_least_squares on column K: its reflection applied to
// the columns after it, r[K][*] filled. False when the pivot is too small (see there).
//
// Every sum runs over i in ascending order exactly as a plain loop per column would, but the
// dot products of the 6 - K later columns advance together in one loop over i: independent
// chains of additions instead of one after the other (the fits are latency-bound on n of about
// 16 to 20 rows); each sum sees the same operations in the same order, so the same bits.
template <int K>
bool householder_step(double* const col[7], std::size_t n, const double norm0[6], double r[6][7],
                      double& sigma) {
  constexpr int kLater = 6 - K;  // columns K + 1 .. 6 (the right-hand side included)
  const double* x = col[K];
  const double alpha = x[K];
  const double norm = std::sqrt(alpha * alpha + sigma);
  const double beta = alpha > 0 ? -norm : norm;
  if (!(std::abs(beta) >= kFastSingularBound * norm0[K]) || norm == 0) return false;
  const double v0 = alpha - beta;
  const double vtv = v0 * v0 + sigma;
  r[K][K] = beta;
  double dot[kLater];
  for (int j = 0; j < kLater; ++j) dot[j] = v0 * col[K + 1 + j][K];
  for (std::size_t i = K + 1; i < n; ++i) {
    const double xi = x[i];
    for (int j = 0; j < kLater; ++j) dot[j] += xi * col[K + 1 + j][i];
  }
  // Column K + 1 first; its part below row K + 1 is final then, and the next step's sum of its
  // squares (in row order, as a loop of its own would take it) advances with the update, while
  // the other columns' updates follow.
  double next_sigma = 0;
  for (int j = 0; j < kLater; ++j) {
    double* y = col[K + 1 + j];
    const double f = 2 * dot[j] / vtv;
    y[K] -= f * v0;
    if (j == 0 && K < 5) {
      y[K + 1] -= f * x[K + 1];
      for (std::size_t i = K + 2; i < n; ++i) {
        y[i] -= f * x[i];
        next_sigma += y[i] * y[i];
      }
    } else {
      for (std::size_t i = K + 1; i < n; ++i) y[i] -= f * x[i];
    }
    r[K][K + 1 + j] = y[K];
  }
  sigma = next_sigma;
  return true;
}

}  // namespace

bool solve_well_posed_least_squares(double* const col[7], std::size_t n, double c[6]) {
  // The six column norms' sums advance together (independent chains, each in row order).
  // With them the first step's sum of squares below its first row (each Householder step
  // returns the next one's: householder_step).
  double sum[6] = {0, 0, 0, 0, 0, 0};
  double sigma = 0;
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 6; ++k) sum[k] += col[k][i] * col[k][i];
    if (i > 0) sigma += col[0][i] * col[0][i];
  }
  double norm0[6];
  for (int k = 0; k < 6; ++k) norm0[k] = std::sqrt(sum[k]);
  double r[6][7];
  if (!(householder_step<0>(col, n, norm0, r, sigma) &&
        householder_step<1>(col, n, norm0, r, sigma) &&
        householder_step<2>(col, n, norm0, r, sigma) &&
        householder_step<3>(col, n, norm0, r, sigma) &&
        householder_step<4>(col, n, norm0, r, sigma) &&
        householder_step<5>(col, n, norm0, r, sigma))) {
    return false;
  }
  if (!(smallest_singular_value_bound(r, norm0) >= kFastSingularBound)) return false;
  for (int k = 5; k >= 0; --k) {
    double sum_k = r[k][6];
    for (int j = k + 1; j < 6; ++j) sum_k -= r[k][j] * c[j];
    c[k] = sum_k / r[k][k];
  }
  return true;
}

double graph_mean_curvature(double fx, double fy, double fxx, double fyy, double fxy) {
  return 0.5 * ((1 + fx * fx) * fyy + (1 + fy * fy) * fxx - 2 * fxy * fx * fy) /
         std::pow(1 + fx * fx + fy * fy, 1.5);
}

QuadricFit QuadricFitter::fit(const Vec3& origin, const std::vector<Vec3>& points,
                              const std::vector<Neighbour>& neighbours) {
  QuadricFit out;
  if (fit_well_posed(origin, points, neighbours, out)) return out;
  return fit_as_reference(origin, points, neighbours);
}

bool QuadricFitter::fit_well_posed(const Vec3& origin, const std::vector<Vec3>& points,
                                   const std::vector<Neighbour>& neighbours, QuadricFit& out) {
  const std::size_t n = neighbours.size();
  if (n < 6) return false;
  const Eigen::Matrix3d moment = covariance(points, neighbours);
  if (!moment.allFinite()) return false;
  eigen3_.compute(moment);
  if (eigen3_.info() != Eigen::Success) return false;
  const Eigen::Vector3d& values = eigen3_.eigenvalues();  // ascending
  if (!(values(1) - values(0) >= kFastEigenGap * std::abs(values(2)))) return false;
  if (!(values(0) >= kFastFlatness * std::abs(values(2)))) return false;
  const Eigen::Vector3d t1 = eigen3_.eigenvectors().col(2);
  const Eigen::Vector3d t2 = eigen3_.eigenvectors().col(1);
  const Eigen::Vector3d normal = eigen3_.eigenvectors().col(0);
  columns_.resize(7 * n);
  double* const col[7] = {&columns_[0],     &columns_[n],     &columns_[2 * n], &columns_[3 * n],
                          &columns_[4 * n], &columns_[5 * n], &columns_[6 * n]};
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& p = points[neighbours[i].index];
    const double v0 = p[0] - origin[0], v1 = p[1] - origin[1], v2 = p[2] - origin[2];
    const double x = v0 * t1(0) + v1 * t1(1) + v2 * t1(2);
    const double y = v0 * t2(0) + v1 * t2(1) + v2 * t2(2);
    col[0][i] = x * x;
    col[1][i] = y * y;
    col[2][i] = x * y;
    col[3][i] = x;
    col[4][i] = y;
    col[5][i] = 1;
    col[6][i] = v0 * normal(0) + v1 * normal(1) + v2 * normal(2);
  }
  double c[6];
  if (!solve_well_posed_least_squares(col, n, c)) return false;
  out.foot = Vec3{origin[0] + c[5] * normal(0), origin[1] + c[5] * normal(1),
                  origin[2] + c[5] * normal(2)};
  out.mean_curvature = graph_mean_curvature(c[3], c[4], 2 * c[0], 2 * c[1], c[2]);
  out.underdetermined = false;
  return true;
}

QuadricFit QuadricFitter::fit_as_reference(const Vec3& origin, const std::vector<Vec3>& points,
                                           const std::vector<Neighbour>& neighbours) {
  const Eigen::Index n = static_cast<Eigen::Index>(neighbours.size());
  if (n == 0) return QuadricFit{origin, 0.0, true};

  const Eigen::Matrix3d moment = covariance(points, neighbours);
  eigen_.compute(moment);
  const Eigen::Vector3d t1 = eigen_.eigenvectors().col(2);
  const Eigen::Vector3d t2 = eigen_.eigenvectors().col(1);
  const Eigen::Vector3d normal = eigen_.eigenvectors().col(0);

  design_.resize(n, 6);
  heights_.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Vec3& p = points[neighbours[static_cast<std::size_t>(i)].index];
    const Eigen::Vector3d v(p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]);
    const double x = v.transpose() * t1;
    const double y = v.transpose() * t2;
    const double z = v.transpose() * normal;
    design_(i, 0) = x * x;
    design_(i, 1) = y * y;
    design_(i, 2) = x * y;
    design_(i, 3) = x;
    design_(i, 4) = y;
    design_(i, 5) = 1;
    heights_(i) = z;
  }
  qr_.compute(design_);
  const Eigen::VectorXd c = qr_.solve(heights_);

  const Eigen::Vector3d delta = c(5) * normal;
  QuadricFit out;
  out.foot = Vec3{origin[0] + delta(0), origin[1] + delta(1), origin[2] + delta(2)};
  // f = a x^2 + b y^2 + c xy + d x + e y + f: fxx = 2a, fyy = 2b, fxy = c, fx = d, fy = e.
  out.mean_curvature = graph_mean_curvature(c(3), c(4), 2 * c(0), 2 * c(1), c(2));
  out.underdetermined = n < 6 || !well_conditioned(qr_, design_);
  return out;
}

}  // namespace qm3d::pointcloud::detail
