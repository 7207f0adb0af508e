#include "halfedge_mesh.h"

#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>

#include <cmath>
#include <limits>
#include <map>

#include "cgal_mesh.h"
#include "qm3d/common/error.h"
#include "triangle_connectivity.h"
#include "vec3_ops.h"

namespace qm3d::mesh::detail {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;

// Repairs a non-manifold soup by duplicating vertices (which become owned copies of the input's),
// recording where each vertex came from.
void build_from_soup(const ColoredMesh& input, std::vector<Triangle> tris, HalfedgeMesh& out,
                     SurfaceMesh& sm) {
  std::vector<Point> points;
  points.reserve(input.positions.size());
  for (const Vec3& p : input.positions) points.emplace_back(p[0], p[1], p[2]);
  std::vector<std::vector<std::size_t>> polygons;
  polygons.reserve(tris.size());
  for (const Triangle& t : tris) polygons.push_back({t[0], t[1], t[2]});
  PMP::orient_polygon_soup(points, polygons);
  // New points are copies of original ones: map them back by their coordinates.
  std::map<std::array<double, 3>, std::uint32_t> first_index;
  for (std::uint32_t i = 0; i < input.positions.size(); ++i) first_index.emplace(input.positions[i], i);
  out.owned_positions = input.positions;
  for (std::size_t i = input.positions.size(); i < points.size(); ++i) {
    const std::array<double, 3> key{points[i].x(), points[i].y(), points[i].z()};
    out.owned_positions.push_back(key);
    out.input_vertex.push_back(first_index.at(key));
  }
  sm.clear();
  PMP::polygon_soup_to_polygon_mesh(points, polygons, sm);
  out.owned_triangles.clear();
  for (auto f : sm.faces()) {
    Triangle t{};
    int k = 0;
    for (auto v : vertices_around_face(sm.halfedge(f), sm)) t[k++] = static_cast<std::uint32_t>(v);
    out.owned_triangles.push_back(t);
  }
}

}  // namespace

RingFaces extract_rings(const SurfaceMesh& sm) {
  RingFaces r;
  r.offsets.reserve(sm.number_of_vertices() + 1);
  r.offsets.push_back(0);
  const std::size_t nh = sm.number_of_halfedges();
  r.source.reserve(nh);
  r.face.reserve(nh);
  r.opposite_face.reserve(nh);
  auto face_id = [&](SurfaceMesh::Halfedge_index h) {
    const auto f = sm.face(h);
    return f == SurfaceMesh::null_face() ? kNoFace : static_cast<std::int32_t>(f);
  };
  for (auto v : sm.vertices()) {
    const auto h0 = sm.halfedge(v);
    if (h0 != SurfaceMesh::null_halfedge()) {
      for (auto h : halfedges_around_target(h0, sm)) {
        r.source.push_back(static_cast<std::uint32_t>(sm.source(h)));
        r.face.push_back(face_id(h));
        r.opposite_face.push_back(face_id(sm.opposite(h)));
      }
    }
    r.offsets.push_back(static_cast<std::uint32_t>(r.source.size()));
  }
  return r;
}

void check_finite(const Vec3& p, std::size_t index, const std::string& name) {
  if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
    throw FormatError(name + ": vertex " + std::to_string(index) + " has a non-finite coordinate");
  }
}

Vec3 face_normal(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = cross(sub(c, b), sub(a, b));
  const double len = norm(n);
  if (len == 0.0) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan, nan};
  }
  return {n[0] / len, n[1] / len, n[2] / len};
}

namespace {

template <typename T>
ArrayView<T> view_of(const std::vector<T>& v) {
  return ArrayView<T>{v.data(), v.size()};
}

}  // namespace

void HalfedgeMesh::detach() {
  if (positions.begin() != owned_positions.data()) {
    owned_positions.assign(positions.begin(), positions.end());
    positions = view_of(owned_positions);
  }
  if (triangles.begin() != owned_triangles.data()) {
    owned_triangles.assign(triangles.begin(), triangles.end());
    triangles = view_of(owned_triangles);
  }
}

namespace {

// The input's triangles without those that repeat a vertex (owned only when some were dropped).
void valid_triangles(const ColoredMesh& mesh, const std::string& name, HalfedgeMesh& out) {
  std::size_t repeated = 0;
  for (const Triangle& t : mesh.triangles) {
    for (auto v : t) {
      if (v >= mesh.positions.size()) {
        throw FormatError(name + ": face refers to vertex " + std::to_string(v) + ", but there are " +
                          std::to_string(mesh.positions.size()) + " vertices");
      }
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) ++repeated;
  }
  out.triangles = view_of(mesh.triangles);
  if (repeated == 0) return;
  for (const Triangle& t : mesh.triangles) {
    if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) out.owned_triangles.push_back(t);
  }
  out.triangles = view_of(out.owned_triangles);
  out.warnings.push_back(name + ": dropped " + std::to_string(repeated) +
                         " faces that repeat a vertex");
}

}  // namespace

HalfedgeMesh build_halfedge_mesh(const ColoredMesh& mesh, const std::string& name,
                                 DegenerateEdges degenerate_edges, int threads) {
  HalfedgeMesh out;
  out.positions = view_of(mesh.positions);
  out.input_vertex.resize(mesh.positions.size());
  for (std::uint32_t i = 0; i < out.input_vertex.size(); ++i) out.input_vertex[i] = i;
  valid_triangles(mesh, name, out);
  if (out.triangles.size() == 0) throw FormatError(name + ": no valid faces");
  // The readers refuse them; a mesh given in memory may hold them (the search trees' median
  // splits need ordered coordinates).
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) check_finite(mesh.positions[v], v, name);

  // Face by face as MEPP2's reader adds them (Euler::add_face), which fails on a non-manifold
  // configuration; such a mesh is repaired into a CGAL Surface_mesh.
  RingFaces rings;
  {
    TriangleConnectivity connectivity(mesh.positions.size(), out.triangles.size());
    bool manifold = true;
    for (const Triangle& t : out.triangles) {
      if (!connectivity.add_face(t)) {
        manifold = false;
        break;
      }
    }
    if (manifold) rings = connectivity.rings();
  }
  if (rings.offsets.empty()) {
    SurfaceMesh sm;
    build_from_soup(mesh, {out.triangles.begin(), out.triangles.end()}, out, sm);
    out.positions = view_of(out.owned_positions);
    out.triangles = view_of(out.owned_triangles);
    out.warnings.push_back(name + ": non-manifold mesh repaired by duplicating " +
                           std::to_string(out.positions.size() - mesh.positions.size()) +
                           " vertices (and re-orienting faces where needed)");
    rings = extract_rings(sm);
  }
  // A triangle's vertices in the order MEPP2 sees them: its reader adds each face with
  // CGAL::Euler::add_face in the file's order, whose halfedge(f) points to the first vertex.
  std::vector<Vec3> normals(out.triangles.size());
  for (std::size_t f = 0; f < out.triangles.size(); ++f) {
    const Triangle& t = out.triangles[f];
    normals[f] = face_normal(out.positions[t[0]], out.positions[t[1]], out.positions[t[2]]);
  }
  out.rings.dihedral =
      dihedral_angles({out.positions.ptr, out.triangles.ptr, normals, rings}, degenerate_edges,
                      threads);
  out.rings.offsets = std::move(rings.offsets);
  out.rings.source = std::move(rings.source);
  return out;
}

}  // namespace qm3d::mesh::detail
