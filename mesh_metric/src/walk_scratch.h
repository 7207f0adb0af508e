// MEPP2's outward walk over the edges around a vertex (used by the curvature tensor and by the
// CMDM / MSDM2 neighbourhoods), with per-thread scratch space (a stack and an O(1)-reset visited
// set). Internal.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "halfedge_mesh.h"
#include "vec3_ops.h"

namespace qm3d::mesh::detail {

/// A stack and a visited stamp per vertex; start() begins a new walk without clearing.
struct WalkScratch {
  std::vector<std::uint32_t> stack;
  std::vector<std::uint32_t> stamp;
  std::uint32_t current = 0;

  void start(std::size_t num_vertices) {
    if (stamp.size() != num_vertices) stamp.assign(num_vertices, 0);
    if (++current == 0) {  // wrapped: reset
      std::fill(stamp.begin(), stamp.end(), 0);
      current = 1;
    }
    stack.clear();
  }
  bool visit(std::uint32_t v) {
    if (stamp[v] == current) return false;
    stamp[v] = current;
    return true;
  }
  /// Walks on from `w` the first time it is entered; false when it already was.
  bool enter(std::uint32_t w) {
    if (!visit(w)) return false;
    stack.push_back(w);
    return true;
  }
};

/// From v0, visits the incoming half-edge k = (w -> v) of every entered vertex v whose edge
/// points away from v0 (always for v0 itself; otherwise (p(w) - p(v)) . (p(v) - p(v0)) >= 0, or
/// > 0 when `strict`), calling on_edge(v, k, w, edge) with edge = p(w) - p(v). on_edge calls
/// scratch.enter(w) to walk on from w (when w lies inside the ball).
template <typename OnEdge>
void walk_outward(const HalfedgeMesh& m, std::uint32_t v0, bool strict, WalkScratch& scratch,
                  OnEdge&& on_edge) {
  const Vec3& o = m.positions[v0];
  scratch.start(m.positions.size());
  scratch.enter(v0);
  while (!scratch.stack.empty()) {
    const std::uint32_t v = scratch.stack.back();
    scratch.stack.pop_back();
    const Vec3& p = m.positions[v];
    const Vec3 p_minus_o = sub(p, o);
    for (std::uint32_t k = m.rings.begin(v); k < m.rings.end(v); ++k) {
      const std::uint32_t w = m.rings.source[k];
      const Vec3 edge = sub(m.positions[w], p);
      const double along = dot(edge, p_minus_o);
      if (v != v0 && !(strict ? along > 0.0 : along >= 0.0)) continue;
      on_edge(v, k, w, edge);
    }
  }
}

}  // namespace qm3d::mesh::detail
