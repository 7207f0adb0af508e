#include "projection.h"

#include <CGAL/AABB_tree/internal/AABB_search_tree.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <numeric>
#include <optional>

#include "cgal_mesh.h"
#include "closest_point.h"
#include "vec3_ops.h"

namespace qm3d::mesh::detail {
namespace {

// CGAL's k-d tree of search hints (its choice among equidistant hints decides ties too) takes
// the AABB traits of MEPP2's tree.
using Traits = FaceTraits;
using HintTree = CGAL::AABB_search_tree<Traits>;
using Hint = Traits::Point_and_primitive_id;

double heron_area(double p, double a, double b, double c) {
  const double s = p * (p - a) * (p - b) * (p - c);
  return s > 0 ? std::sqrt(s) : 0.0;
}

// MEPP2 matching_multires_update: sub-triangle areas from the corner distances.
std::array<double, 3> heron_areas(const HalfedgeMesh& mesh, std::uint32_t face, const Vec3& q) {
  const Triangle& t = mesh.triangles[face];
  const Vec3 &x1 = mesh.positions[t[0]], &x2 = mesh.positions[t[1]], &x3 = mesh.positions[t[2]];
  const double l1 = distance(x3, x2), l2 = distance(x1, x3), l3 = distance(x1, x2);
  const double t1 = distance(x1, q), t2 = distance(x2, q), t3 = distance(x3, q);
  const double p1 = (l1 + t2 + t3) / 2, p2 = (t1 + l2 + t3) / 2, p3 = (t1 + t2 + l3) / 2;
  return {heron_area(p1, l1, t3, t2), heron_area(p2, l2, t3, t1), heron_area(p3, l3, t1, t2)};
}

// CGAL's k-d tree (Kd_tree::create_internal_node, Sliding_midpoint) splits a node whose points
// all coincide by sliding one point off (Point_container::split), so a group of k equal hints
// makes a chain k levels deep: 256 bytes of stack a level in the build, and its search recurses
// as deep. 60,000 copies of one face overflow an 8 MB stack. Up to this many coincident hints
// the tree gets the hints exactly as MEPP2's does (the same tree, the same answers, ties
// included); past it (MEPP2 itself recurses tens of thousands of levels there, and crashes) only
// the first hint of each group of equal points, so that the tree is never deeper than its
// distinct points make it.
constexpr std::size_t kMaxCoincidentHints = 1024;

// FNV-1a over the bits of coordinates, -0 taken as +0 (equal coordinates hash alike).
std::uint64_t hash_coordinates(std::uint64_t h, double x) {
  std::uint64_t bits;
  x = x == 0 ? 0.0 : x;
  std::memcpy(&bits, &x, sizeof bits);
  return (h ^ bits) * 1099511628211ull;
}

constexpr std::uint64_t kHashSeed = 1469598103934665603ull;

std::uint64_t position_hash(const Vec3& p) {
  std::uint64_t h = kHashSeed;
  for (double x : p) h = hash_coordinates(h, x);
  return h;
}

// Groups of hints at equal positions. Hints are given as vertices (key[e] for hint e); for each
// hint, the group it is in, whether it is its group's first, and the size of the largest group.
class CoincidentHints {
 public:
  CoincidentHints(const ArrayView<Vec3>& positions, const std::vector<std::uint32_t>& key) {
    const std::vector<std::uint32_t> first_vertex = first_coincident(positions);
    std::vector<std::uint32_t> first_hint(positions.size(), kNone), count(positions.size(), 0);
    group_.resize(key.size());
    for (std::uint32_t e = 0; e < key.size(); ++e) {
      const std::uint32_t g = first_vertex[key[e]];
      group_[e] = g;
      if (first_hint[g] == kNone) first_hint[g] = e;
      largest_ = std::max<std::size_t>(largest_, ++count[g]);
    }
    first_.resize(key.size());
    shared_.resize(key.size());
    for (std::uint32_t e = 0; e < key.size(); ++e) {
      first_[e] = first_hint[group_[e]] == e;
      shared_[e] = count[group_[e]] > 1;
    }
  }

  std::size_t largest() const { return largest_; }
  bool first(std::uint32_t e) const { return first_[e] != 0; }
  /// Another hint is at the same position.
  bool shared(std::uint32_t e) const { return shared_[e] != 0; }

 private:
  static constexpr std::uint32_t kNone = 0xffffffffu;

  // For each vertex, the smallest index of a vertex at the same position. Equal positions hash
  // alike, so a vertex alone in its hash bucket is alone at its position: only the others are
  // sorted by position (then index) to find their groups.
  static std::vector<std::uint32_t> first_coincident(const ArrayView<Vec3>& positions) {
    std::vector<std::uint32_t> first(positions.size());
    std::iota(first.begin(), first.end(), 0u);
    std::size_t buckets = 1;
    while (buckets < 2 * positions.size()) buckets <<= 1;
    const auto bucket_of = [&](std::uint32_t v) {
      return position_hash(positions[v]) & (buckets - 1);
    };
    std::vector<std::uint32_t> count(buckets, 0);
    for (std::uint32_t v = 0; v < positions.size(); ++v) ++count[bucket_of(v)];
    std::vector<std::uint32_t> order;
    for (std::uint32_t v = 0; v < positions.size(); ++v) {
      if (count[bucket_of(v)] > 1) order.push_back(v);
    }
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
      return positions[a] < positions[b] || (positions[a] == positions[b] && a < b);
    });
    for (std::size_t i = 1; i < order.size(); ++i) {
      if (positions[order[i - 1]] == positions[order[i]]) first[order[i]] = first[order[i - 1]];
    }
    return first;
  }

  std::vector<std::uint32_t> group_;
  std::vector<char> first_, shared_;
  std::size_t largest_ = 0;
};

// The closest-point search starts from a hint: a point on the mesh and its face, the nearest of
// a set of samples in CGAL's k-d tree. When a query projects onto an edge or a vertex, the hint
// decides which of the equidistant faces is reported. MSDM2 measures its Heron distances from
// the off-surface query, so that choice moves its score (by 6e-5 on blob4_geonoise): it gets
// CGAL's default samples exactly as MEPP2's tree takes them (one per face, its first corner, in
// face order). CMDM interpolates at the projected point, where the tied faces agree, and gets one
// sample per vertex instead (its first face), found by NearestPointIndex on the distinct
// positions: the same hint as CGAL's k-d tree wherever the nearest sample is unique; where
// another is exactly as near (a coincident vertex, or another at the same distance), CGAL's k-d
// tree, built on first need, decides. Groups of coincident samples larger than
// kMaxCoincidentHints are given to CGAL's tree as their first sample only.
class SearchHints {
 public:
  SearchHints(const HalfedgeMesh& target, HeronAnchor anchor, int threads) : target_(target) {
    if (anchor == HeronAnchor::kQueryPoint) {
      std::vector<std::uint32_t> faces(target.triangles.size()), corners(faces.size());
      std::iota(faces.begin(), faces.end(), 0u);
      for (std::uint32_t f = 0; f < faces.size(); ++f) corners[f] = target.triangles[f][0];
      cgal_ = cgal_hints(corners, faces);
      return;
    }
    const std::vector<std::uint32_t> faces = vertex_faces();
    for (std::uint32_t v = 0; v < faces.size(); ++v) {
      if (faces[v] != kNone) vertices_.push_back(v);
    }
    groups_.emplace(target.positions, vertices_);
    std::vector<std::uint32_t> distinct, hint_of(faces.size(), 0);
    for (std::uint32_t e = 0; e < vertices_.size(); ++e) {
      hint_of[vertices_[e]] = e;
      if (groups_->first(e)) distinct.push_back(vertices_[e]);
    }
    index_.emplace(target.positions, distinct, hint_of, threads);
    vertex_face_ = faces;
  }

  ClosestPoint operator()(const Vec3& q) const {
    if (index_) {
      const NearestPointIndex::Nearest n = index_->nearest(q);
      if (!n.tie && !groups_->shared(n.id)) return {n.point, vertex_face_[vertices_[n.id]]};
      std::call_once(cgal_built_, [this] {
        std::vector<std::uint32_t> faces(vertices_.size());
        for (std::size_t e = 0; e < faces.size(); ++e) faces[e] = vertex_face_[vertices_[e]];
        cgal_ = cgal_hints(vertices_, faces);
      });
    }
    const Hint h = cgal_->closest_point(to_point(q));
    return {{h.first.x(), h.first.y(), h.first.z()}, h.second};
  }

 private:
  static constexpr std::uint32_t kNone = 0xffffffffu;

  // The first face of each vertex (kNone for a vertex without faces).
  std::vector<std::uint32_t> vertex_faces() const {
    std::vector<std::uint32_t> face(target_.positions.size(), kNone);
    for (std::uint32_t f = 0; f < target_.triangles.size(); ++f) {
      for (auto v : target_.triangles[f]) {
        if (face[v] == kNone) face[v] = f;
      }
    }
    return face;
  }

  // CGAL's k-d tree of the hints (the position of vertex corners[e], face faces[e]) in their
  // order; only the first of each group of equal positions when a group is too large.
  std::unique_ptr<HintTree> cgal_hints(const std::vector<std::uint32_t>& corners,
                                       const std::vector<std::uint32_t>& faces) const {
    const CoincidentHints groups(target_.positions, corners);
    const bool all = groups.largest() <= kMaxCoincidentHints;
    std::vector<Hint> hints;
    hints.reserve(corners.size());
    for (std::uint32_t e = 0; e < corners.size(); ++e) {
      if (all || groups.first(e))
        hints.emplace_back(to_point(target_.positions[corners[e]]), faces[e]);
    }
    return std::make_unique<HintTree>(hints.begin(), hints.end());
  }

  const HalfedgeMesh& target_;
  std::vector<std::uint32_t> vertices_;     ///< CMDM: the vertices with a face, in order
  std::vector<std::uint32_t> vertex_face_;  ///< CMDM: the first face of each vertex
  std::optional<CoincidentHints> groups_;   ///< CMDM: the coincident groups of vertices_
  std::optional<NearestPointIndex> index_;
  mutable std::once_flag cgal_built_;
  mutable std::unique_ptr<HintTree> cgal_;
};

// Faces repeated (the same corner positions in the same order) more than this many times go
// into the closest-point tree once: a query on such a face visits every copy (each copy's box
// reaches it and none is pruned), n^2 work for n copies of a face and n queries on it. Below it
// the tree holds every face, as MEPP2's does.
constexpr std::size_t kMaxRepeatedFaces = 1024;

// The faces the closest-point tree holds: every face of the mesh (`all`), or the first copy of
// each geometry, with the mesh's face of each tree face and the tree face of each mesh face.
struct TreeFaces {
  bool all = true;
  std::vector<Triangle> triangles;
  std::vector<std::uint32_t> mesh_face;
  std::vector<std::uint32_t> tree_face;
};

std::array<double, 9> corners_of(const HalfedgeMesh& m, std::uint32_t f) {
  const Triangle& t = m.triangles[f];
  const Vec3 &a = m.positions[t[0]], &b = m.positions[t[1]], &c = m.positions[t[2]];
  return {a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2]};
}

// The size of the largest set of faces with one geometry, bounded above by the largest set with
// one hash of it (equal geometries hash alike): the exact count is needed only past the bound.
// That in turn is bounded by the largest set with the same low 16 bits of the hash, counted in
// one pass; the hashes are sorted only when that bound does not settle it (repeated faces).
std::size_t largest_hash_run(const HalfedgeMesh& m, std::size_t enough) {
  std::vector<std::uint64_t> hashes(m.triangles.size());
  constexpr std::size_t kBuckets = 1u << 16;
  std::vector<std::uint32_t> bucket(kBuckets, 0);
  std::size_t largest = 0;
  for (std::uint32_t f = 0; f < hashes.size(); ++f) {
    std::uint64_t h = kHashSeed;
    for (double x : corners_of(m, f)) h = hash_coordinates(h, x);
    hashes[f] = h;
    largest = std::max<std::size_t>(largest, ++bucket[h & (kBuckets - 1)]);
  }
  if (largest <= enough) return largest;
  std::sort(hashes.begin(), hashes.end());
  largest = 0;
  for (std::size_t i = 0, run = 0; i < hashes.size(); ++i) {
    run = i > 0 && hashes[i] == hashes[i - 1] ? run + 1 : 1;
    largest = std::max(largest, run);
  }
  return largest;
}

TreeFaces tree_faces(const HalfedgeMesh& m) {
  TreeFaces out;
  if (largest_hash_run(m, kMaxRepeatedFaces) <= kMaxRepeatedFaces) return out;
  std::vector<std::uint32_t> order(m.triangles.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return corners_of(m, a) < corners_of(m, b);
  });
  std::vector<std::uint32_t> first(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    const bool starts = i == 0 || corners_of(m, order[i - 1]) != corners_of(m, order[i]);
    first[order[i]] = starts ? order[i] : first[order[i - 1]];
  }
  out.all = false;
  out.tree_face.resize(order.size());
  for (std::uint32_t f = 0; f < order.size(); ++f) {
    if (first[f] == f) {
      out.tree_face[f] = static_cast<std::uint32_t>(out.triangles.size());
      out.triangles.push_back(m.triangles[f]);
      out.mesh_face.push_back(f);
    } else {
      out.tree_face[f] = out.tree_face[first[f]];
    }
  }
  return out;
}

}  // namespace

// What a target surface needs for closest-point queries: its search hints, the faces its tree
// holds and CGAL's AABB tree over them.
struct SurfaceTarget::Impl {
  Impl(const HalfedgeMesh& m, HeronAnchor a, int threads)
      : mesh(m),
        anchor(a),
        hints(m, a, threads),
        faces(tree_faces(m)),
        tree(m.positions,
             faces.all ? m.triangles
                       : ArrayView<Triangle>{faces.triangles.data(), faces.triangles.size()},
             threads) {}

  const HalfedgeMesh& mesh;
  HeronAnchor anchor;
  SearchHints hints;
  TreeFaces faces;
  FaceBoxTree tree;
};

SurfaceTarget::SurfaceTarget(const HalfedgeMesh& target, HeronAnchor anchor, int threads)
    : impl_(std::make_unique<Impl>(target, anchor, threads)) {}

SurfaceTarget::~SurfaceTarget() = default;

void SurfaceTarget::match(const Vec3& v, Vec3& point, SurfaceMatch& m) const {
  const Impl& t = *impl_;
  ClosestPoint c;
  if (t.faces.all) {
    c = t.tree.closest(v, t.hints(v));
  } else {
    ClosestPoint hint = t.hints(v);
    hint.face = t.faces.tree_face[hint.face];
    c = t.tree.closest(v, hint);
    c.face = t.faces.mesh_face[c.face];
  }
  point = c.point;
  m.face = c.face;
  m.areas = heron_areas(t.mesh, m.face, t.anchor == HeronAnchor::kProjectedPoint ? c.point : v);
}

SurfaceMatches match_to_surface(const ArrayView<Vec3>& queries, const HalfedgeMesh& target,
                                HeronAnchor anchor, int threads) {
  const SurfaceTarget surface(target, anchor, threads);
  return std::move(match_to_surfaces({{queries, &surface}}, threads).front());
}

std::vector<SurfaceMatches> match_to_surfaces(const std::vector<SurfaceQueries>& sets,
                                              int threads) {
  std::vector<SurfaceMatches> out(sets.size());
  std::vector<std::int64_t> start(sets.size() + 1, 0);  // each set's first index in the loop
  for (std::size_t s = 0; s < sets.size(); ++s) {
    out[s].points.resize(sets[s].queries.size());
    out[s].matches.resize(sets[s].queries.size());
    start[s + 1] = start[s] + static_cast<std::int64_t>(sets[s].queries.size());
  }
  const std::int64_t n = start.back();
#pragma omp parallel for schedule(dynamic, 1024) num_threads(threads)
  for (std::int64_t i = 0; i < n; ++i) {
    const std::size_t s = static_cast<std::size_t>(std::upper_bound(start.begin(), start.end(), i) -
                                                   start.begin() - 1);
    const auto j = static_cast<std::size_t>(i - start[s]);
    sets[s].target->match(sets[s].queries[j], out[s].points[j], out[s].matches[j]);
  }
  return out;
}

double interpolate(const SurfaceMatch& m, const Triangle& t, const std::vector<double>& values) {
  return interpolate(m, values[t[0]], values[t[1]], values[t[2]]);
}

}  // namespace qm3d::mesh::detail
