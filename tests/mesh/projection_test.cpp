// match_to_surface (projection.h) against MEPP2's CGAL calls themselves: the same closest point
// and face for every query, bit for bit. MSDM2's hints are CGAL's own (its AABB tree's k-d tree
// of the faces' first corners); CMDM's are CGAL's k-d tree of one sample per vertex, which qm3d
// answers from the distinct positions and leaves to CGAL on ties. Checked on smooth, noisy and
// quantised meshes and on one whose vertices all come in coincident pairs (every CMDM hint a tie).
#include "projection.h"

#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_tree/internal/AABB_search_tree.h>
#include <gtest/gtest.h>

#include <boost/iterator/counting_iterator.hpp>
#include <cstring>

#include "../test_paths.h"
#include "cgal_mesh.h"
#include "qm3d/mesh/mesh_io.h"

namespace qm3d::mesh::detail {
namespace {

using Tree = CGAL::AABB_tree<FaceTraits>;
using HintTree = CGAL::AABB_search_tree<FaceTraits>;

bool same_bits(const Vec3& a, const Kernel::Point_3& b) {
  const Vec3 c{b.x(), b.y(), b.z()};
  return std::memcmp(&a, &c, sizeof(Vec3)) == 0;
}

HalfedgeMesh view_of(const ColoredMesh& m) {
  HalfedgeMesh mesh;  // views of the arrays: all match_to_surface reads
  mesh.positions = {m.positions.data(), m.positions.size()};
  mesh.triangles = {m.triangles.data(), m.triangles.size()};
  return mesh;
}

// CGAL's k-d tree of one hint per vertex (its first face), in vertex order.
HintTree vertex_hints(const ColoredMesh& m) {
  std::vector<std::uint32_t> face(m.positions.size(), 0xffffffffu);
  for (std::uint32_t f = 0; f < m.triangles.size(); ++f) {
    for (auto v : m.triangles[f]) {
      if (face[v] == 0xffffffffu) face[v] = f;
    }
  }
  std::vector<Tree::Point_and_primitive_id> hints;
  for (std::uint32_t v = 0; v < face.size(); ++v) {
    if (face[v] != 0xffffffffu) hints.emplace_back(to_point(m.positions[v]), face[v]);
  }
  return HintTree(hints.begin(), hints.end());
}

void expect_mepp2s_matches(const ColoredMesh& target, const std::vector<Vec3>& queries) {
  const HalfedgeMesh mesh = view_of(target);
  Tree cgal(boost::counting_iterator<std::uint32_t>(0),
            boost::counting_iterator<std::uint32_t>(std::uint32_t(target.triangles.size())),
            FaceTriangleMap{&mesh}, FacePointMap{&mesh});
  cgal.accelerate_distance_queries();
  cgal.build();
  const HintTree per_vertex = vertex_hints(target);
  const ArrayView<Vec3> q{queries.data(), queries.size()};
  for (const HeronAnchor anchor : {HeronAnchor::kQueryPoint, HeronAnchor::kProjectedPoint}) {
    const SurfaceMatches ours = match_to_surface(q, mesh, anchor, 2);
    for (std::size_t i = 0; i < queries.size(); ++i) {
      const Point p = to_point(queries[i]);
      const auto expected = anchor == HeronAnchor::kQueryPoint
                                ? cgal.closest_point_and_primitive(p)
                                : cgal.closest_point_and_primitive(p, per_vertex.closest_point(p));
      ASSERT_EQ(ours.matches[i].face, expected.second) << "query " << i;
      ASSERT_TRUE(same_bits(ours.points[i], expected.first)) << "query " << i;
    }
  }
}

ColoredMesh reference_mesh(const std::string& dir, const std::string& name) {
  return read_mesh(test::reference_dir() / dir / name).mesh;
}

TEST(MatchToSurface, GivesMepp2sPointAndFaceOnReferenceMeshes) {
  const ColoredMesh ref = reference_mesh("cmdm", "blob4_ref.off");
  const ColoredMesh noisy = reference_mesh("cmdm", "blob4_geonoise.off");
  expect_mepp2s_matches(ref, noisy.positions);
  expect_mepp2s_matches(noisy, ref.positions);
  expect_mepp2s_matches(ref, ref.positions);
  const ColoredMesh q6 = reference_mesh("quantised", "blob5_pquant6.off");
  const ColoredMesh blob5 = reference_mesh("cmdm", "blob5_ref.off");
  expect_mepp2s_matches(q6, blob5.positions);
  expect_mepp2s_matches(blob5, q6.positions);
}

// Every vertex twice (faces alternate between the copies): every CMDM hint is a tie.
TEST(MatchToSurface, GivesMepp2sPointAndFaceWhenEveryVertexHasATwin) {
  ColoredMesh twin = reference_mesh("cmdm", "blob4_ref.off");
  const auto n = static_cast<std::uint32_t>(twin.positions.size());
  twin.positions.insert(twin.positions.end(), twin.positions.begin(), twin.positions.end());
  twin.colors.insert(twin.colors.end(), twin.colors.begin(), twin.colors.end());
  for (std::size_t f = 1; f < twin.triangles.size(); f += 2) {
    for (auto& v : twin.triangles[f]) v += n;
  }
  const ColoredMesh noisy = reference_mesh("cmdm", "blob4_geonoise.off");
  expect_mepp2s_matches(twin, noisy.positions);
  expect_mepp2s_matches(twin, twin.positions);
}

}  // namespace
}  // namespace qm3d::mesh::detail
