// Curvature-tensor estimation on a geodesic-like ball (Cohen-Steiner & Morvan's normal cycle, as
// MEPP2 implements it), post-processed into one scalar per vertex. Internal.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

#include "halfedge_mesh.h"
#include "qm3d/common/progress.h"

namespace qm3d::mesh::detail {

enum class CurvatureVariant {
  /// MEPP2 curvature_cmdm.hpp (SPEC-CMDM 1.5): only non-border edges that cross the sphere
  /// contribute; the walk test is ">= 0".
  kCmdm,
  /// MEPP2's generic curvature.hpp as MSDM2 uses it (SPEC-CMDM 2): every non-border edge inside
  /// the ball contributes (clipped where it crosses); the walk test is "> 0".
  kGeneric,
};

/// maxdim * (|k1| + |k2|) / 2 per vertex, where k1, k2 are the two principal curvatures of
/// largest magnitude of the tensor accumulated within `radius` (SPEC-CMDM 1.5 step 7); 0 at a
/// vertex whose tensor reaches an edge marked kVoidsTensor (the mesh's DegenerateEdges rule).
/// Parallel over vertices with `threads` OpenMP threads; the result does not depend on them.
std::vector<double> processed_curvature(const HalfedgeMesh& mesh, double radius, double maxdim,
                                        CurvatureVariant variant, int threads);

/// processed_curvature at each of `radii` (which must not decrease), from one walk per vertex
/// (walk_outward_levels): the same edges contribute at each radius as in a walk at that radius
/// alone, summed in another order, so the values may differ from processed_curvature's by
/// rounding. MEPP2's walks are written one radius at a time; the metrics use this one, and the
/// tests check one against the other. Each vertex done is counted in `progress` (may be null).
std::vector<std::vector<double>> processed_curvatures(const HalfedgeMesh& mesh,
                                                      const std::vector<double>& radii,
                                                      double maxdim, CurvatureVariant variant,
                                                      int threads,
                                                      LoopProgress* progress = nullptr);

/// The absolute epsilon of MEPP2's sphere_clip_vector: an edge vector whose squared length is
/// below it is taken as inside the sphere, whatever the radius (MEPP2 commit d977d05,
/// FEVV/Operators/Geometry/ClippingAndIntersection.hpp, `fabs(a) < epsilon` on a = v . v; the
/// curvature of both CMDM, curvature_cmdm.hpp, and MSDM2, Manifold/Curvature/curvature.hpp,
/// goes through it). Reproduced, so the curvature features are not scale-invariant on meshes
/// with edges shorter than sqrt(epsilon) = 1.5e-8 (in the mesh's units).
constexpr double kClipEpsilon = std::numeric_limits<double>::epsilon();

/// Edges shorter than sqrt(kClipEpsilon), each counted once: those of length zero (two
/// vertices at one position, e.g. merged by quantisation: inside every sphere at any scale) and
/// the others (inside every sphere only because the mesh is small: scale-dependent).
struct ShortEdges {
  std::size_t zero = 0;
  std::size_t tiny = 0;
};
ShortEdges edges_under_clip_epsilon(const HalfedgeMesh& mesh);

/// MEPP2's sphere_clip_vector (ClippingAndIntersection.hpp): clips `v`, starting at `p`, to the
/// sphere (o, r). Returns true when the segment crosses the sphere ("isect").
bool sphere_clip_vector(const Vec3& o, double r, const Vec3& p, Vec3& v);

}  // namespace qm3d::mesh::detail
