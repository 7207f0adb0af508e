// Signed dihedral angle of every edge as MEPP2's curvature estimation sees it (SPEC-CMDM 1.5
// step 4), computed once per mesh. Internal.
//
// MEPP2 evaluates beta = asin(((n1 x n2) . v) / |v|) on the clipped edge vector v every time an
// edge is visited; since v is the edge scaled by a positive factor, the angle depends on the edge
// only, so it is computed here once per half-edge. It differs from MEPP2's by rounding only, but
// asin amplifies that near +-1: on blob5 quantised to 6 bits this alone moves local MSDM2 values
// by up to 5e-9.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "qm3d/common/types.h"

namespace qm3d::mesh::detail {

inline constexpr std::int32_t kNoFace = -1;

/// How an edge next to degenerate geometry enters the curvature tensor: an edge of zero length,
/// or an edge of a face whose unit normal is NaN (its three vertices are collinear). The two MEPP2
/// curvature codes differ here.
enum class DegenerateEdges {
  /// MEPP2 curvature_cmdm.hpp (SPEC-CMDM 1.5 step 4): a NaN normal is replaced by the normal of
  /// another face on the same edge endpoints (beta = 0 if there is none, or if both are NaN),
  /// edges of a face whose three vertices coincide and zero-length edges contribute nothing, and
  /// exactly opposite normals give beta = 0.
  kRepaired,
  /// MEPP2's generic curvature.hpp (SPEC-CMDM §MSDM2-degenerate): no special case. Such an edge
  /// gets beta = NaN there (0/0 or a NaN normal), which makes the whole tensor of every vertex
  /// whose ball reaches it NaN; Eigen's solver then fails and MEPP2 sets that vertex's curvature
  /// to 0 at that scale. Here the edge is marked kVoidsTensor and the curvature set to 0 directly.
  kVoidTensor,
};

/// Stored for an edge that never contributes: a border edge, or (kRepaired) an edge of a face
/// whose three vertices coincide.
inline constexpr double kNoContribution = std::numeric_limits<double>::quiet_NaN();
/// Stored (kVoidTensor) for a non-border edge whose angle MEPP2's generic code computes as NaN.
inline constexpr double kVoidsTensor = std::numeric_limits<double>::infinity();

/// Incoming half-edges (w -> v) of every vertex with the faces on either side.
struct RingFaces {
  std::vector<std::uint32_t> offsets;       ///< #V + 1
  std::vector<std::uint32_t> source;        ///< w of each incoming half-edge
  std::vector<std::int32_t> face;           ///< face on the half-edge's side (kNoFace on a border)
  std::vector<std::int32_t> opposite_face;  ///< face on the other side
};

struct DihedralInput {
  const Vec3* positions = nullptr;
  const Triangle* triangles = nullptr;
  const std::vector<Vec3>& face_normals;  ///< unit normals, NaN for collinear triangles
  const RingFaces& rings;
};

/// beta of each incoming half-edge under `rule`; kNoContribution or kVoidsTensor where the edge
/// has no angle. Parallel over vertices with `threads` OpenMP threads.
std::vector<double> dihedral_angles(const DihedralInput& m, DegenerateEdges rule, int threads);

}  // namespace qm3d::mesh::detail
