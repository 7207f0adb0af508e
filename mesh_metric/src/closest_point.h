// Closest points on a triangle mesh exactly as CGAL 5.5's AABB tree finds them with
// Simple_cartesian<double> (AABB_tree.h, AABB_tree/internal/AABB_node.h, AABB_traits.h and the
// kernel's point-triangle projection), node for node: the same tree (each node's faces split at
// the median of their reference points along the longest axis of its box, by the same
// std::nth_element calls), the same depth-first traversal from the same hint, the same
// sphere-box test and the same rule for replacing the closest point, so that even among faces
// at equal distance the same face is reported. MEPP2 finds its matches with that tree, and which
// of the equidistant faces it reports moves the scores of quantised meshes (by 3e-6 relative on
// blob5 quantised to 6 bits with another choice). What differs is the cost: the tree is built
// in parallel, its nodes are 48-byte boxes in an implicit pre-order layout (CGAL's: 64 bytes
// with two pointers) and faces are read from the mesh's arrays without property maps. Internal.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "halfedge_mesh.h"

namespace qm3d::mesh::detail {

/// The point of triangle (a, b, c) closest to q, computed as CGAL 5.5's
/// Construct_projected_point_3(Triangle_3, Point_3) computes it with Simple_cartesian<double>
/// (Kernel/function_objects.h): q projected on the supporting plane, kept when inside, else
/// moved onto the first edge it lies beyond (in the order ab, bc, ca) or the nearest corner; a
/// triangle whose plane is degenerate is replaced by its longest edge. Same bits as CGAL's.
Vec3 project_on_triangle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& q);

/// A point on the mesh and the face it was found on.
struct ClosestPoint {
  Vec3 point{0, 0, 0};
  std::uint32_t face = 0;
};

/// Exact nearest-neighbour search in a set of points with ids (the closest-point search's hints),
/// telling also whether another point is exactly as near: only then does the answer depend on
/// the order of the search (CGAL's k-d tree decides such ties by its own). Distances are computed
/// as CGAL's Euclidean_distance computes them. A k-d tree of median splits, built in parallel.
class NearestPointIndex {
 public:
  /// The points positions[v] for v in `which`, each with the id ids[v] (`ids` has one entry per
  /// position; only those of `which` are read).
  NearestPointIndex(const ArrayView<Vec3>& positions, const std::vector<std::uint32_t>& which,
                    const std::vector<std::uint32_t>& ids, int threads);

  struct Nearest {
    Vec3 point{0, 0, 0};
    std::uint32_t id = 0;
    bool tie = false;  ///< another point is at the same (computed) squared distance
  };
  /// The nearest point (at least one point must have been given).
  Nearest nearest(const Vec3& q) const;

 private:
  struct Split {
    double value = 0;
    std::uint32_t right = 0;  ///< the right child's node (the left one follows its parent)
    int dim = 0;
  };
  struct Search;
  void build(std::vector<std::uint32_t>& order, std::size_t node, std::uint32_t first,
             std::uint32_t count, const ArrayView<Vec3>& positions);
  void search(std::size_t node, std::uint32_t first, std::uint32_t count, Search& s) const;

  std::vector<Vec3> points_;  ///< in tree order
  std::vector<std::uint32_t> ids_;
  std::vector<Split> splits_;  ///< one per node (unused in leaves), pre-order
};

/// CGAL's AABB_tree over the faces of a mesh (primitives in face order, each face's reference
/// point its first corner), for closest-point queries.
class FaceBoxTree {
 public:
  /// Builds over every triangle (at least one) with up to `threads` OpenMP threads; the arrays
  /// must outlive the tree.
  FaceBoxTree(const ArrayView<Vec3>& positions, const ArrayView<Triangle>& triangles,
              int threads);

  /// CGAL's closest_point_and_primitive(q, hint): the hint (a point on the mesh and its face)
  /// is kept unless a face visited by the traversal is at most as far and gives another point.
  ClosestPoint closest(const Vec3& q, const ClosestPoint& hint) const;

 private:
  struct Box {
    Vec3 lo, hi;
  };
  struct Search;
  Box bounds(std::uint32_t first, std::uint32_t count) const;
  void build(std::size_t node, std::uint32_t first, std::uint32_t count);
  void visit_face(std::uint32_t face, Search& s) const;
  void traverse(std::size_t node, std::uint32_t first, std::uint32_t count, Search& s) const;

  ArrayView<Vec3> positions_;
  ArrayView<Triangle> triangles_;
  std::vector<std::uint32_t> faces_;  ///< CGAL's primitives, in the order the build leaves them
  std::vector<Box> boxes_;            ///< the #faces - 1 inner nodes, pre-order
};

}  // namespace qm3d::mesh::detail
