// Signed dihedral angle of every edge as MEPP2's curvature estimation sees it (SPEC-CMDM 1.5
// step 4), computed once per mesh. Internal.
//
// MEPP2 evaluates beta = asin(((n1 x n2) . v) / |v|) on the clipped edge vector v every time an
// edge is visited; since v is the edge scaled by a positive factor, the angle depends on the edge
// only, so it is computed here once per half-edge.
#pragma once

#include <cstdint>
#include <vector>

#include "qm3d/common/types.h"

namespace qm3d::mesh::detail {

inline constexpr std::int32_t kNoFace = -1;

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

/// beta of each incoming half-edge; NaN where the edge never contributes (border edge, or a
/// face whose three vertices coincide).
std::vector<double> dihedral_angles(const DihedralInput& m);

}  // namespace qm3d::mesh::detail
