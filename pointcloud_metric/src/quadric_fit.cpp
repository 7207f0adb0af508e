#include "quadric_fit.h"

#include <cmath>

namespace qm3d::pointcloud::detail {
namespace {

/// A fit counts as underdetermined below this scaled pivot ratio: its least-squares solution is
/// then sensitive to rounding beyond 1e-9 relative (about 1e-16 / ratio), so the QR
/// implementation's rounding shows in the result.
constexpr double kConditionLimit = 1e-7;

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

}  // namespace

double graph_mean_curvature(double fx, double fy, double fxx, double fyy, double fxy) {
  return 0.5 * ((1 + fx * fx) * fyy + (1 + fy * fy) * fxx - 2 * fxy * fx * fy) /
         std::pow(1 + fx * fx + fy * fy, 1.5);
}

QuadricFit QuadricFitter::fit(const Vec3& origin, const std::vector<Vec3>& points,
                              const std::vector<Neighbour>& neighbours) {
  const Eigen::Index n = static_cast<Eigen::Index>(neighbours.size());
  if (n == 0) return QuadricFit{origin, 0.0, true};

  // Covariance as E[x x^T] - mu mu^T. Each entry is summed in neighbour order exactly as the
  // reference's `M = M + neighbor * neighbor.transpose()` does, but in registers.
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
  const double count = static_cast<double>(n);
  const Eigen::Vector3d mean(sx / count, sy / count, sz / count);
  const double inv = 1. / count;
  Eigen::Matrix3d moment;
  moment << inv * sxx - mean(0) * mean(0), inv * sxy - mean(0) * mean(1),
      inv * sxz - mean(0) * mean(2),  //
      inv * sxy - mean(1) * mean(0), inv * syy - mean(1) * mean(1), inv * syz - mean(1) * mean(2),
      inv * sxz - mean(2) * mean(0), inv * syz - mean(2) * mean(1), inv * szz - mean(2) * mean(2);

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
