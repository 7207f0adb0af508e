#include "triangle_connectivity.h"

#include <utility>

namespace qm3d::mesh::detail {

TriangleConnectivity::TriangleConnectivity(std::size_t vertices, std::size_t faces)
    : vertex_halfedge_(vertices, kNull) {
  // A closed mesh has 3 half-edges per face; borders add a few.
  const std::size_t halfedges = 3 * faces + 6;
  next_.reserve(halfedges);
  prev_.reserve(halfedges);
  target_.reserve(halfedges);
  face_.reserve(halfedges);
}

std::uint32_t TriangleConnectivity::next_around_target(std::uint32_t h) const {
  const std::uint32_t n = next_[h];
  return n == kNull ? kNull : opposite(n);
}

// BGL is_border(vertex): some half-edge around the vertex's half-edge is a border one.
bool TriangleConnectivity::on_border(std::uint32_t v) const {
  const std::uint32_t h0 = vertex_halfedge_[v];
  std::uint32_t h = h0;
  for (std::size_t guard = 0; guard <= next_.size(); ++guard) {
    if (is_border(h)) return true;
    h = next_around_target(h);
    if (h == kNull || h == h0) return false;
  }
  return false;
}

// Surface_mesh::halfedge(source, target): circulates around `to` from its half-edge.
std::uint32_t TriangleConnectivity::find_halfedge(std::uint32_t from, std::uint32_t to) const {
  const std::uint32_t h0 = vertex_halfedge_[to];
  if (h0 == kNull) return kNull;
  std::uint32_t h = h0;
  for (std::size_t guard = 0; guard <= next_.size(); ++guard) {
    if (source(h) == from) return h;
    h = next_around_target(h);
    if (h == kNull || h == h0) return kNull;
  }
  return kNull;
}

// Surface_mesh::add_edge(from, to): a new pair of half-edges (from -> to first), unlinked.
std::uint32_t TriangleConnectivity::new_edge(std::uint32_t from, std::uint32_t to) {
  const auto h = static_cast<std::uint32_t>(next_.size());
  for (std::uint32_t t : {to, from}) {
    next_.push_back(kNull);
    prev_.push_back(kNull);
    target_.push_back(t);
    face_.push_back(kNoFace);
  }
  return h;
}

void TriangleConnectivity::set_next(std::uint32_t h, std::uint32_t next) {
  next_[h] = next;
  prev_[next] = h;
}

// CGAL::internal::adjust_incoming_halfedge: the vertex's half-edge becomes a border half-edge
// into it when there is one.
void TriangleConnectivity::adjust_incoming_halfedge(std::uint32_t v) {
  std::uint32_t h = vertex_halfedge_[v];
  if (h == kNull) return;
  if (target_[h] != v) {
    h = opposite(h);
    vertex_halfedge_[v] = h;
  }
  const std::uint32_t h0 = h;
  for (std::size_t guard = 0; guard <= next_.size(); ++guard) {
    if (is_border(h)) {
      vertex_halfedge_[v] = h;
      return;
    }
    h = next_around_target(h);
    if (h == kNull || h == h0) return;
  }
}

bool TriangleConnectivity::add_face(const std::array<std::uint32_t, 3>& vertices) {
  constexpr unsigned n = 3;
  if (vertices[0] == vertices[1] || vertices[1] == vertices[2] || vertices[0] == vertices[2]) {
    return false;
  }
  std::array<std::uint32_t, n> halfedges{};
  std::array<bool, n> is_new{};
  for (unsigned i = 0, ii = 1; i < n; ++i, ++ii, ii %= n) {
    const std::uint32_t v = vertices[i];
    if (vertex_halfedge_[v] != kNull && !on_border(v)) return false;
    halfedges[i] = find_halfedge(v, vertices[ii]);
    is_new[i] = halfedges[i] == kNull;
    if (!is_new[i] && !is_border(halfedges[i])) return false;
  }

  // set_next calls are collected and made at the end, as CGAL's next_cache does.
  std::array<std::pair<std::uint32_t, std::uint32_t>, 6 * n> next_cache;
  std::size_t cached = 0;
  const auto cache = [&](std::uint32_t h, std::uint32_t next) { next_cache[cached++] = {h, next}; };

  // Re-link patches if necessary.
  for (unsigned i = 0, ii = 1; i < n; ++i, ++ii, ii %= n) {
    if (is_new[i] || is_new[ii]) continue;
    const std::uint32_t inner_prev = halfedges[i], inner_next = halfedges[ii];
    if (next_[inner_prev] == inner_next) continue;
    // A free gap between border_prev and border_next.
    const std::uint32_t outer_prev = opposite(inner_next);
    std::uint32_t border_prev = outer_prev;
    std::size_t guard = 0;
    do {
      if (next_[border_prev] == kNull || ++guard > next_.size()) return false;
      border_prev = opposite(next_[border_prev]);
    } while (!is_border(border_prev) || border_prev == inner_prev);
    const std::uint32_t border_next = next_[border_prev];
    if (border_next == inner_next) return false;
    const std::uint32_t patch_start = next_[inner_prev], patch_end = prev_[inner_next];
    cache(border_prev, patch_start);
    cache(patch_end, border_next);
    cache(inner_prev, inner_next);
  }

  // Missing edges.
  for (unsigned i = 0, ii = 1; i < n; ++i, ++ii, ii %= n) {
    if (is_new[i]) halfedges[i] = new_edge(vertices[i], vertices[ii]);
  }
  const std::int32_t f = faces_++;

  // Half-edge links and vertex half-edges.
  for (unsigned i = 0, ii = 1; i < n; ++i, ++ii, ii %= n) {
    const std::uint32_t v = vertices[ii];
    const std::uint32_t inner_prev = halfedges[i], inner_next = halfedges[ii];
    const unsigned id = (is_new[i] ? 1u : 0u) | (is_new[ii] ? 2u : 0u);
    if (id != 0) {
      const std::uint32_t outer_prev = opposite(inner_next);
      const std::uint32_t outer_next = opposite(inner_prev);
      switch (id) {
        case 1: {  // prev is new, next is old
          const std::uint32_t border_prev = prev_[inner_next];
          cache(border_prev, outer_next);
          vertex_halfedge_[v] = border_prev;
          break;
        }
        case 2: {  // next is new, prev is old
          const std::uint32_t border_next = next_[inner_prev];
          cache(outer_prev, border_next);
          vertex_halfedge_[v] = outer_prev;
          break;
        }
        default: {  // both are new: try to pick a border half-edge with v as target
          std::uint32_t hv = vertex_halfedge_[v];
          if (hv != kNull && !is_border(hv)) {
            std::uint32_t h = hv;
            for (std::size_t guard = 0; guard <= next_.size(); ++guard) {
              if (is_border(h)) {
                hv = h;
                break;
              }
              h = next_around_target(h);
              if (h == kNull || h == vertex_halfedge_[v]) break;
            }
            if (!is_border(hv)) hv = kNull;
          }
          if (hv == kNull) {
            vertex_halfedge_[v] = outer_prev;
            cache(outer_prev, outer_next);
          } else {
            const std::uint32_t border_next = next_[hv];
            cache(hv, outer_next);
            cache(outer_prev, border_next);
          }
          break;
        }
      }
      cache(inner_prev, inner_next);
    }
    face_[inner_prev] = f;
  }

  for (std::size_t k = 0; k < cached; ++k) set_next(next_cache[k].first, next_cache[k].second);
  for (std::uint32_t v : vertices) adjust_incoming_halfedge(v);
  return true;
}

RingFaces TriangleConnectivity::rings() const {
  RingFaces r;
  r.offsets.reserve(vertex_halfedge_.size() + 1);
  r.offsets.push_back(0);
  r.source.reserve(next_.size());
  r.face.reserve(next_.size());
  r.opposite_face.reserve(next_.size());
  for (const std::uint32_t h0 : vertex_halfedge_) {
    if (h0 != kNull) {
      std::uint32_t h = h0;
      for (std::size_t guard = 0; guard < next_.size(); ++guard) {
        r.source.push_back(source(h));
        r.face.push_back(face_[h]);
        r.opposite_face.push_back(face_[opposite(h)]);
        h = next_around_target(h);
        if (h == kNull || h == h0) break;
      }
    }
    r.offsets.push_back(static_cast<std::uint32_t>(r.source.size()));
  }
  return r;
}

}  // namespace qm3d::mesh::detail
