// The CGAL types the mesh module works with, shared with the tests that compare its own
// structures with CGAL's: the kernel, the Surface_mesh and the vertex rings read from it, and
// the faces as MEPP2's AABB tree sees them. Internal.
#pragma once

#include <CGAL/AABB_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>

#include <cstdint>

#include "dihedral.h"
#include "halfedge_mesh.h"

namespace qm3d::mesh::detail {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;

inline Point to_point(const Vec3& p) { return Point(p[0], p[1], p[2]); }

/// The incoming half-edges of every vertex of `sm`, circulated from the vertex's half-edge
/// (halfedges_around_target), with the faces on either side.
RingFaces extract_rings(const SurfaceMesh& sm);

/// Property maps giving a face's triangle and its reference point (its first corner), built from
/// the mesh's arrays on demand, so that CGAL's AABB structures hold face indices only.
struct FaceTriangleMap {
  const HalfedgeMesh* mesh = nullptr;
  using key_type = std::uint32_t;
  using value_type = Kernel::Triangle_3;
  using reference = Kernel::Triangle_3;
  using category = boost::readable_property_map_tag;
  friend Kernel::Triangle_3 get(const FaceTriangleMap& m, std::uint32_t f) {
    const auto& t = m.mesh->triangles[f];
    const auto& p = m.mesh->positions;
    return {to_point(p[t[0]]), to_point(p[t[1]]), to_point(p[t[2]])};
  }
};

struct FacePointMap {
  const HalfedgeMesh* mesh = nullptr;
  using key_type = std::uint32_t;
  using value_type = Point;
  using reference = Point;
  using category = boost::readable_property_map_tag;
  friend Point get(const FacePointMap& m, std::uint32_t f) {
    return to_point(m.mesh->positions[m.mesh->triangles[f][0]]);
  }
};

/// A face as a primitive of CGAL's AABB traits: its index, with the maps above.
using FacePrimitive = CGAL::AABB_primitive<std::uint32_t, FaceTriangleMap, FacePointMap,
                                           CGAL::Tag_true /*external maps*/, CGAL::Tag_false>;
using FaceTraits = CGAL::AABB_traits<Kernel, FacePrimitive>;

}  // namespace qm3d::mesh::detail
