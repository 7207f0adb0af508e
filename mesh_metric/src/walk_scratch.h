// MEPP2's outward walk over the edges around a vertex (used by the curvature tensor and by the
// CMDM / MSDM2 neighbourhoods), with per-thread scratch space (a stack and an O(1)-reset visited
// set). Internal.
#pragma once

#include <algorithm>
#include <cstdint>
#include <utility>
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

/// WalkScratch plus the edges that crossed the sphere at the current radius, to be tested again
/// at the next one.
struct MultiWalkScratch : WalkScratch {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pending, next;  ///< (vertex, half-edge)
};

/// walk_outward at `levels` radii at once, the smallest first: at_level(level, v, k, w, edge)
/// tests edge k = (w -> v) at that level's radius, calls scratch.enter(w) when w lies inside and
/// returns true when the edge crosses the sphere; end_level(level) follows each level's last edge.
///
/// Why one walk serves every radius: a vertex lies in the ball of radius r iff some chain of
/// outward edges from v0 reaches it with every edge's far end inside, and MEPP2's clip tests
/// (sphere_clip_vector and its CMDM variant) are monotone in r for a given edge (a larger r
/// lowers c = |w|^2 - r^2, which raises delta and t, and every IEEE operation involved is
/// monotone). So the ball at level j is the ball at level j - 1 grown from the edges that crossed
/// there: those are tested again at level j, every other outward edge once, at the level at which
/// its vertex was entered (an edge inside at one level is inside at every larger radius). Each
/// level thus sees exactly the edges and vertices of a walk at its radius alone, in another order.
template <typename AtLevel, typename EndLevel>
void walk_outward_levels(const HalfedgeMesh& m, std::uint32_t v0, bool strict, std::size_t levels,
                         MultiWalkScratch& scratch, AtLevel&& at_level, EndLevel&& end_level) {
  const Vec3& o = m.positions[v0];
  scratch.start(m.positions.size());
  scratch.pending.clear();
  scratch.enter(v0);
  for (std::size_t level = 0; level < levels; ++level) {
    const bool last = level + 1 == levels;
    scratch.next.clear();
    const auto test = [&](std::uint32_t v, std::uint32_t k, const Vec3& edge) {
      if (at_level(level, v, k, m.rings.source[k], edge) && !last) scratch.next.emplace_back(v, k);
    };
    for (const auto& [v, k] : scratch.pending) {
      test(v, k, sub(m.positions[m.rings.source[k]], m.positions[v]));
    }
    while (!scratch.stack.empty()) {
      const std::uint32_t v = scratch.stack.back();
      scratch.stack.pop_back();
      const Vec3 p_minus_o = sub(m.positions[v], o);
      for (std::uint32_t k = m.rings.begin(v); k < m.rings.end(v); ++k) {
        const Vec3 edge = sub(m.positions[m.rings.source[k]], m.positions[v]);
        const double along = dot(edge, p_minus_o);
        if (v != v0 && !(strict ? along > 0.0 : along >= 0.0)) continue;
        test(v, k, edge);
      }
    }
    std::swap(scratch.pending, scratch.next);
    end_level(level);
  }
}

}  // namespace qm3d::mesh::detail
