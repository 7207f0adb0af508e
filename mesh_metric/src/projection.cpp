#include "projection.h"

#include <CGAL/AABB_tree/internal/AABB_search_tree.h>
#include <boost/iterator/counting_iterator.hpp>
#include <boost/iterator/transform_iterator.hpp>

#include <cmath>
#include <memory>
#include <mutex>
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

// The closest-point search starts from a hint: a point on the mesh and its face, the nearest of
// a set of samples in CGAL's k-d tree. When a query projects onto an edge or a vertex, the hint
// decides which of the equidistant faces is reported. MSDM2 measures its Heron distances from
// the off-surface query, so that choice moves its score (by 6e-5 on blob4_geonoise): it gets
// CGAL's default samples exactly as MEPP2's tree takes them (one per face, its first corner, in
// face order). CMDM interpolates at the projected point, where the tied faces agree, and gets one
// sample per vertex instead (its first face), found by NearestPointIndex: the same hint as CGAL's
// k-d tree wherever the nearest sample is unique; where another is exactly as near (coincident
// vertices), CGAL's k-d tree, built on first need, decides.
class SearchHints {
 public:
  SearchHints(const HalfedgeMesh& target, HeronAnchor anchor, int threads) : target_(target) {
    if (anchor == HeronAnchor::kQueryPoint) {
      const auto to_hint = [&](std::uint32_t f) {
        return Hint(to_point(target.positions[target.triangles[f][0]]), f);
      };
      const boost::counting_iterator<std::uint32_t> first(0);
      const boost::counting_iterator<std::uint32_t> last(
          static_cast<std::uint32_t>(target.triangles.size()));
      cgal_ = std::make_unique<HintTree>(boost::make_transform_iterator(first, to_hint),
                                         boost::make_transform_iterator(last, to_hint));
      return;
    }
    const std::vector<std::uint32_t> faces = vertex_faces();
    std::vector<std::uint32_t> vertices;
    for (std::uint32_t v = 0; v < faces.size(); ++v) {
      if (faces[v] != kNone) vertices.push_back(v);
    }
    index_.emplace(target.positions, vertices, faces, threads);
  }

  ClosestPoint operator()(const Vec3& q) const {
    if (index_) {
      const NearestPointIndex::Nearest n = index_->nearest(q);
      if (!n.tie) return {n.point, n.id};
      std::call_once(cgal_built_, [this] { cgal_ = cgal_vertex_hints(); });
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

  // CGAL's k-d tree of the vertex samples, given in vertex order.
  std::unique_ptr<HintTree> cgal_vertex_hints() const {
    const std::vector<std::uint32_t> faces = vertex_faces();
    std::vector<Hint> hints;
    for (std::uint32_t v = 0; v < faces.size(); ++v) {
      if (faces[v] != kNone) hints.emplace_back(to_point(target_.positions[v]), faces[v]);
    }
    return std::make_unique<HintTree>(hints.begin(), hints.end());
  }

  const HalfedgeMesh& target_;
  std::optional<NearestPointIndex> index_;
  mutable std::once_flag cgal_built_;
  mutable std::unique_ptr<HintTree> cgal_;
};

}  // namespace

SurfaceMatches match_to_surface(const ArrayView<Vec3>& queries, const HalfedgeMesh& target,
                                HeronAnchor anchor, int threads) {
  const SearchHints hints(target, anchor, threads);
  const FaceBoxTree tree(target.positions, target.triangles, threads);
  SurfaceMatches out;
  out.points.resize(queries.size());
  out.matches.resize(queries.size());
  const auto n = static_cast<std::int64_t>(queries.size());
#pragma omp parallel for schedule(dynamic, 1024) num_threads(threads)
  for (std::int64_t i = 0; i < n; ++i) {
    const Vec3& v = queries[std::size_t(i)];
    const ClosestPoint c = tree.closest(v, hints(v));
    out.points[std::size_t(i)] = c.point;
    SurfaceMatch& m = out.matches[std::size_t(i)];
    m.face = c.face;
    m.areas = heron_areas(target, m.face, anchor == HeronAnchor::kProjectedPoint ? c.point : v);
  }
  return out;
}

double interpolate(const SurfaceMatch& m, const Triangle& t, const std::vector<double>& values) {
  const auto& a = m.areas;
  const double sum = a[0] + a[1] + a[2];
  if (sum > 0) return (a[0] * values[t[0]] + a[1] * values[t[1]] + a[2] * values[t[2]]) / sum;
  return (values[t[0]] + values[t[1]] + values[t[2]]) / 3;
}

}  // namespace qm3d::mesh::detail
