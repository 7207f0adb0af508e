// PCA normals as ../shared/tools/add_pca_normals.py computes them with its defaults (k = 12,
// --orient centroid), bit for bit: the normals that tool wrote into reference/mpeg/vox1_ref_n.ply,
// which pc_error's D2 reads. Used by `psnr --normals estimate`.
//
// The tool's steps and where each rule is reproduced (pca_normals.cpp):
// - neighbours: the 12 nearest points, the point itself included, by exact squared distance in
//   double ((dx² + dy²) + dz²) from the float32 coordinates; at equal distance the lower file
//   index wins (numpy.partition, then a lexsort by (distance, index));
// - covariance: C = (1/12) Σ (q − m)(q − m)ᵀ about the 12 points' mean m, both sums taken
//   sequentially over the 12 points in that order and divided by 12 (numpy's mean and einsum);
// - eigenvector of the smallest eigenvalue as numpy.linalg.eigh returns it: LAPACK's dsyevd
//   (UPLO 'L'), which for a 3x3 matrix runs dsytd2 (one Householder reflector), dsteqr (implicit
//   QL/QR with its shifts, splits and selection sort) and dorm2r. symmetric_eigenvectors_3x3
//   follows those routines operation by operation (Reference-LAPACK 3.11, netlib BLAS), because a
//   generic solver (Eigen's) differs in the rounding noise LAPACK leaves in exact-zero components
//   (±1.1e-16, signed zeros) and float32 keeps that noise;
// - orientation: flip n when n · (p − c) < 0, c the mean of all points, the dot product summed
//   (n₀d₀ + n₂d₂) + n₁d₁ as numpy's einsum does with two SIMD lanes; a flip negates every
//   component (0 becomes −0);
// - the normal is rounded to float32.
#pragma once

#include <array>
#include <vector>

#include "qm3d/common/types.h"

namespace qm3d::pointcloud::detail {

/// Neighbourhood size of add_pca_normals.py (--k default), the point itself included.
inline constexpr int kPcaNeighbours = 12;

/// Normals as ../shared/tools/add_pca_normals.py computes them (defaults), one per point,
/// float32 like the tool writes; OpenMP over points (`threads`, 0 = the OpenMP default), the same
/// bits for any thread count. Throws NumericError for fewer than 12 points (the tool fails there).
std::vector<std::array<float, 3>> estimate_pca_normals(const std::vector<Vec3>& positions,
                                                       int threads);

/// Eigen-decomposition of a symmetric 3x3 matrix (only its lower triangle is read, row-major
/// `a[row][col]`) as LAPACK's dsyevd('V', 'L') returns it: eigenvalues ascending and
/// `vectors[i]` the unit eigenvector of `values[i]`, with LAPACK's signs and rounding.
/// \bug LAPACK's rescaling of matrices whose largest entry is below ~1e-146 or above ~1e146 is
/// not reproduced (coordinates beyond ~1e±73).
struct SymmetricEigen3 {
  std::array<double, 3> values{};
  std::array<Vec3, 3> vectors{};
};
SymmetricEigen3 symmetric_eigenvectors_3x3(const std::array<Vec3, 3>& a);

}  // namespace qm3d::pointcloud::detail
