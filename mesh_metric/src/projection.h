// Closest-point correspondence between a vertex set and a triangle mesh (CGAL AABB tree), and
// MEPP2's Heron-formula interpolation of vertex attributes at the matched point. Internal.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "halfedge_mesh.h"

namespace qm3d::mesh::detail {

/// The face a query matched on the target surface and the Heron sub-triangle areas used to
/// interpolate the target's vertex attributes there (SPEC-CMDM 1.6).
struct SurfaceMatch {
  std::uint32_t face = 0;
  std::array<double, 3> areas{};  ///< a1, a2, a3: areas opposite each corner of `face`
};

/// The closest point of each query on the target surface, and how to interpolate there.
struct SurfaceMatches {
  std::vector<Vec3> points;
  std::vector<SurfaceMatch> matches;
};

/// Which point the Heron distances are measured from.
enum class HeronAnchor {
  kProjectedPoint,  ///< CMDM: the matched point q(v) on the surface
  kQueryPoint,      ///< MSDM2: the query vertex itself (off the surface)
};

/// A target surface ready for closest-point queries: its search hints and the AABB tree over its
/// faces, built with up to `threads` OpenMP threads. The mesh must outlive it and stay in place.
class SurfaceTarget {
 public:
  SurfaceTarget(const HalfedgeMesh& target, HeronAnchor anchor, int threads);
  ~SurfaceTarget();
  SurfaceTarget(const SurfaceTarget&) = delete;
  SurfaceTarget& operator=(const SurfaceTarget&) = delete;

  /// The closest point of query `q` on the surface and how to interpolate there.
  void match(const Vec3& q, Vec3& point, SurfaceMatch& m) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// For each query, the closest point on `target` and its interpolation areas. Parallel over the
/// queries with `threads` OpenMP threads.
SurfaceMatches match_to_surface(const ArrayView<Vec3>& queries, const HalfedgeMesh& target,
                                HeronAnchor anchor, int threads);

/// A set of queries and the surface they are matched on.
struct SurfaceQueries {
  ArrayView<Vec3> queries;
  const SurfaceTarget* target;
};

/// The matches of every set, in one parallel loop over all their queries (so that the threads
/// share the work of sets of unequal cost); each match is what match_to_surface gives.
std::vector<SurfaceMatches> match_to_surfaces(const std::vector<SurfaceQueries>& sets, int threads);

/// (a1 x1 + a2 x2 + a3 x3) / (a1 + a2 + a3), or the plain average when all areas are 0,
/// written as MEPP2's matching_multires_update does (x1, x2, x3: the values at the corners of
/// the matched face).
inline double interpolate(const SurfaceMatch& m, double x1, double x2, double x3) {
  const auto& a = m.areas;
  const double sum = a[0] + a[1] + a[2];
  if (sum > 0) return (a[0] * x1 + a[1] * x2 + a[2] * x3) / sum;
  return (x1 + x2 + x3) / 3;
}

/// interpolate with the corner values values[t[0]], values[t[1]], values[t[2]].
double interpolate(const SurfaceMatch& m, const Triangle& t, const std::vector<double>& values);

}  // namespace qm3d::mesh::detail
