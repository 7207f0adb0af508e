// How a polygon becomes triangles: one rule for a mesh's faces (mesh_io.cpp) and for the
// texture corners of the same faces (texture.cpp). Internal.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

namespace qm3d::mesh::detail {

/// Polygons of up to this many corners are fan-triangulated from their first corner, as qm3d
/// always did (their scores do not change). The fan of a larger polygon gives its first corner a
/// face per corner and covers the polygon with slivers: the half-edge build circulates that
/// corner at every face (N^2 for N corners), a closest-point query on the rim visits the boxes
/// of most slivers (N^2), and the slivers' rounding moved the score of a 100k-corner disc
/// against itself to 6.3e-4.
constexpr std::uint32_t kMaxFanCorners = 1024;

/// Calls emit(a, b, c) for each triangle of a polygon of `corners` (>= 3) corners, given as
/// corner positions 0..corners-1 in the polygon's order (its orientation kept): a fan from corner
/// 0 up to kMaxFanCorners corners; else a balanced split, the triangle (first, middle, last) of
/// a chain of corners and then both halves of the chain, so that every corner is in O(log N)
/// triangles and the triangles shrink by half at each level.
template <typename Emit>
void triangulate_polygon(std::uint32_t corners, Emit emit) {
  if (corners <= kMaxFanCorners) {
    for (std::uint32_t k = 1; k + 1 < corners; ++k) emit(0u, k, k + 1);
    return;
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> chains{{0u, corners - 1}};
  while (!chains.empty()) {
    const auto [first, last] = chains.back();
    chains.pop_back();
    if (last - first < 2) continue;
    const std::uint32_t middle = first + (last - first) / 2;
    emit(first, middle, last);
    chains.push_back({middle, last});
    chains.push_back({first, middle});  // depth first: each triangle shares an edge with one made
  }
}

}  // namespace qm3d::mesh::detail
