// D_LAB's mesh side (pointcloud_metric/src/dlab.cpp has the metric): each vertex of one mesh
// matched on the other mesh's surface exactly as CMDM matches it (projection.h:
// match_to_surface with HeronAnchor::kProjectedPoint on the halfedge mesh CMDM builds), with the
// colour there interpolated as CMDM interpolates its colour features (multiscale.cpp
// interpolate_colors: each LAB2000HL channel of the face's three vertices weighted by the Heron
// sub-triangle areas, projection.h interpolate).
#include <omp.h>

#include "halfedge_mesh.h"
#include "projection.h"
#include "qm3d/common/error.h"
#include "qm3d/mesh/metrics.h"

namespace qm3d::mesh {
namespace {

const ColoredMesh& coloured_mesh(const Input& input) {
  const MeshData& m = input.mesh();
  if (!m.has_colors || m.mesh.colors.size() != m.mesh.positions.size()) {
    throw FormatError(input.name() +
                      ": no vertex colours (dlab compares colours: one colour per vertex needed)");
  }
  return m.mesh;
}

// LAB2000HL of each vertex of the halfedge mesh (vertices duplicated by its repairs take their
// input vertex's colour, as multiscale.cpp does).
std::vector<Lab> halfedge_lab(const detail::HalfedgeMesh& m, const ColoredMesh& input,
                              const Lab2000hlTable& table) {
  std::vector<Lab> lab = to_lab2000hl(input.colors, table);
  for (std::size_t v = lab.size(); v < m.input_vertex.size(); ++v) {
    lab.push_back(lab[m.input_vertex[v]]);
  }
  return lab;
}

// The interpolated colour at a match. A match on a corner (two of the three areas exactly 0)
// takes that corner's colour: the interpolation's exact value, which (a x) / a could round by an
// ulp, so that identical meshes give exactly 0.
Lab colour_at(const detail::SurfaceMatch& m, const Triangle& t, const std::vector<Lab>& lab,
              const std::vector<double> (&channels)[3]) {
  const auto& a = m.areas;
  for (int k = 0; k < 3; ++k) {
    if (a[k] > 0 && a[(k + 1) % 3] == 0 && a[(k + 2) % 3] == 0) return lab[t[k]];
  }
  return {detail::interpolate(m, t, channels[0]), detail::interpolate(m, t, channels[1]),
          detail::interpolate(m, t, channels[2])};
}

}  // namespace

SurfaceColours match_surface_colours(const Input& iterated, const Input& other,
                                     const Lab2000hlTable& table, int threads) {
  const int n_threads = threads > 0 ? threads : omp_get_max_threads();
  const ColoredMesh& own_mesh = coloured_mesh(iterated);
  const ColoredMesh& other_mesh = coloured_mesh(other);
  // CMDM's rule for degenerate edges (kCmdmDefinition); the projection does not depend on it.
  const detail::HalfedgeMesh target = detail::build_halfedge_mesh(
      other_mesh, other.name(), detail::DegenerateEdges::kRepaired, n_threads);
  const std::vector<Lab> target_lab = halfedge_lab(target, other_mesh, table);
  std::vector<double> channels[3];
  for (auto& c : channels) c.resize(target_lab.size());
  for (std::size_t v = 0; v < target_lab.size(); ++v) {
    channels[0][v] = target_lab[v].L;
    channels[1][v] = target_lab[v].a;
    channels[2][v] = target_lab[v].b;
  }
  const detail::ArrayView<Vec3> queries{own_mesh.positions.data(), own_mesh.positions.size()};
  const detail::SurfaceMatches matches =
      detail::match_to_surface(queries, target, detail::HeronAnchor::kProjectedPoint, n_threads);
  SurfaceColours out;
  out.own = to_lab2000hl(own_mesh.colors, table);
  out.matched.resize(matches.matches.size());
  for (std::size_t v = 0; v < out.matched.size(); ++v) {
    const detail::SurfaceMatch& m = matches.matches[v];
    out.matched[v] = colour_at(m, target.triangles[m.face], target_lab, channels);
  }
  out.warnings = target.warnings;
  return out;
}

}  // namespace qm3d::mesh
