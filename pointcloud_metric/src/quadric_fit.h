// The local quadric fit of MEPP-team/PCQM (`computeProjectionAndCurvature`, SPEC-PCQM 1.4 step 2):
// PCA frame of the neighbours, least-squares height field z = a x^2 + b y^2 + c xy + d x + e y + f
// around the query point, foot point and mean curvature at x = y = 0.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "kd_tree.h"
#include "qm3d/common/types.h"

namespace qm3d::pointcloud::detail {

struct QuadricFit {
  Vec3 foot{0, 0, 0};         ///< origin + f n: the origin projected onto the fitted surface
  /// H at the origin (in inverse coordinate units), signed along the normal, whose orientation
  /// is the eigen-solver's (either path may choose the other one: |H| and `foot` do not depend
  /// on it).
  double mean_curvature = 0;
  /// The six coefficients are not determined by the points, or barely: fewer than six points,
  /// too few distinct positions, or a design so ill-conditioned (scaled pivot ratio below 1e-7)
  /// that the solution moves beyond 1e-9 with rounding. The solution is then the QR's "basic"
  /// one, or its rounding, which differs between Eigen versions (SPEC-PCQM §9.5).
  bool underdetermined = false;
};

/// Fits quadrics; holds the workspaces so that one fitter per thread allocates little.
///
/// Two paths give the same fit to rounding (the least-squares problem has one solution):
/// * a fast one for well-posed fits (nearly all): Eigen's fixed-size 3x3 eigen-solver and an
///   unpivoted Householder QR of the n x 6 design of our own, on flat arrays;
/// * the reference's, for everything else (fewer than six points, a barely separated normal,
///   a design whose unit-column form is not clearly well-conditioned, non-finite input), where the
///   reference's rounding decides the value (SPEC-PCQM §9.5).
///
/// The reference's path is bit-for-bit its arithmetic: raw second moment minus the mean's outer product,
/// `SelfAdjointEigenSolver<MatrixXd>` (the dynamic-size solver: the fixed 3x3 one rounds
/// differently), frame t1 = largest, t2 = middle, n = smallest eigenvector, coordinates relative
/// to the origin, `ColPivHouseholderQR<MatrixXd>` (its basic solution when there are fewer than
/// six points). With no neighbour at all the result is the origin and H = 0, which is what the
/// reference's QR returns for an empty system (without its NaN foot point); such a fit is
/// underdetermined too.
class QuadricFitter {
 public:
  /// `neighbours` index `points`; their order is the summation order.
  QuadricFit fit(const Vec3& origin, const std::vector<Vec3>& points,
                 const std::vector<Neighbour>& neighbours);

  /// The reference's path alone (what fit() falls back to).
  QuadricFit fit_as_reference(const Vec3& origin, const std::vector<Vec3>& points,
                              const std::vector<Neighbour>& neighbours);

 private:
  /// The fast path; false (and `out` untouched) when the fit is not clearly well-posed.
  bool fit_well_posed(const Vec3& origin, const std::vector<Vec3>& points,
                      const std::vector<Neighbour>& neighbours, QuadricFit& out);

  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen3_;
  std::vector<double> columns_;  ///< the fast path's design, column by column, then the heights
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen_{3};
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr_;
  Eigen::MatrixXd design_;
  Eigen::VectorXd heights_;
};

/// The least-squares solution c of the n x 6 system held column by column in `col` (col[0..5]
/// the design, col[6] the right-hand side; each n long, overwritten), by an unpivoted
/// Householder QR. False (c undefined) when the design with unit columns is not clearly
/// well-conditioned (its smallest singular value below 1e-2, or a pivot below that share of its
/// column's norm): the solution would then depend on the solver's rounding, and the caller
/// decides (PCQM: the reference's QR; PointSSIM: a minimum-norm solve). Both quadric fits of
/// the module (QuadricFitter, pointssim_fit.cpp) solve their well-posed systems here.
bool solve_well_posed_least_squares(double* const col[7], std::size_t n, double c[6]);

/// Mean curvature of the graph of z = f(x, y) at the origin from f's first and second
/// derivatives (do Carmo, "Differential Geometry of Curves and Surfaces", 3-3, ex. 21), written
/// as the reference writes it.
double graph_mean_curvature(double fx, double fy, double fxx, double fyy, double fxy);

}  // namespace qm3d::pointcloud::detail
