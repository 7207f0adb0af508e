// The connectivity the CMDM / MSDM2 walks need, in flat arrays: built face by face as CGAL's
// Surface_mesh builds it (triangle_connectivity.h), or taken from a CGAL Surface_mesh when a
// non-manifold input has to be repaired (the Surface_mesh is released: memory stays low on large
// meshes). Internal.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "dihedral.h"
#include "qm3d/common/types.h"

namespace qm3d::mesh::detail {

/// Incoming half-edges (w -> v) of every vertex v, in CGAL's circulation order around v.
struct VertexRings {
  std::vector<std::uint32_t> offsets;  ///< #V + 1
  std::vector<std::uint32_t> source;   ///< w of each incoming half-edge
  /// Signed dihedral angle of the edge under the mesh's DegenerateEdges rule (dihedral.h);
  /// kNoContribution when the edge never contributes to the curvature tensor, kVoidsTensor when
  /// it voids the tensor of the vertices whose curvature estimate reaches it.
  std::vector<double> dihedral;

  std::uint32_t begin(std::uint32_t v) const { return offsets[v]; }
  std::uint32_t end(std::uint32_t v) const { return offsets[v + 1]; }
};

/// A read-only view of an array (the input's, or one the mesh owns after a repair).
template <typename T>
struct ArrayView {
  const T* ptr = nullptr;
  std::size_t count = 0;

  const T& operator[](std::size_t i) const { return ptr[i]; }
  std::size_t size() const { return count; }
  const T* begin() const { return ptr; }
  const T* end() const { return ptr + count; }
};

/// A triangle mesh ready for the metric: positions, triangles, vertex rings with edge angles.
/// Positions and triangles are the input mesh's own arrays (no copy) unless a repair had to
/// change them or detach() was called; the input must outlive the views.
struct HalfedgeMesh {
  HalfedgeMesh() = default;
  HalfedgeMesh(HalfedgeMesh&&) = default;
  HalfedgeMesh(const HalfedgeMesh&) = delete;
  HalfedgeMesh& operator=(const HalfedgeMesh&) = delete;
  HalfedgeMesh& operator=(HalfedgeMesh&&) = default;  // vector moves keep the viewed buffers

  ArrayView<Vec3> positions;
  ArrayView<Triangle> triangles;
  VertexRings rings;
  /// Index in the input mesh of each vertex (non-manifold vertices are duplicated, like MEPP2's
  /// reader does, so a vertex of the input may appear more than once).
  std::vector<std::uint32_t> input_vertex;
  std::vector<std::string> warnings;

  // Storage used when the input had to be repaired, or after detach() (views above point here
  // then).
  std::vector<Vec3> owned_positions;
  std::vector<Triangle> owned_triangles;

  /// Copies the arrays still viewed in the input into the mesh's own storage: the input may be
  /// freed afterwards.
  void detach();
};

/// Builds the connectivity and the edges' dihedral angles under `degenerate_edges`. Faces with a
/// repeated vertex are dropped with a warning; non-manifold configurations are repaired by
/// duplicating vertices (CGAL's orient_polygon_soup), with a warning. `name` names the mesh in
/// messages; `threads` OpenMP threads compute the angles.
HalfedgeMesh build_halfedge_mesh(const ColoredMesh& mesh, const std::string& name,
                                 DegenerateEdges degenerate_edges, int threads);

/// Throws FormatError "<name>: vertex <index> has a non-finite coordinate" unless p is finite
/// (the readers check every vertex they read; build_halfedge_mesh checks meshes given in memory).
void check_finite(const Vec3& p, std::size_t index, const std::string& name);

/// Unit normal of face (a, b, c) as MEPP2 computes it: calculate_face_normal.hpp takes the
/// face's first vertex a as p0 and returns CGAL::unit_normal(b, c, a) = (c - b) x (a - b),
/// divided by its length; all components NaN when that cross product is exactly zero. The order
/// matters: on nearly collinear triangles another order rounds to zero, or not, elsewhere.
Vec3 face_normal(const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace qm3d::mesh::detail
