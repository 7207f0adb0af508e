// TriangleConnectivity (triangle_connectivity.h) against CGAL's Surface_mesh built with the same
// faces in the same order: every add_face succeeds or fails alike, and the vertex rings (sources
// and faces, in circulation order from each vertex's half-edge) are equal, on closed meshes,
// meshes with borders, shuffled face orders (which make Euler::add_face re-link patches) and
// soups full of non-manifold faces.
#include "triangle_connectivity.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "../test_paths.h"
#include "cgal_mesh.h"
#include "qm3d/mesh/mesh_io.h"

namespace qm3d::mesh::detail {
namespace {

// Adds every face to both (after a failure too: both leave the mesh as it was) and compares.
// Returns how many faces were refused.
std::size_t expect_same_as_cgal(std::size_t vertices, const std::vector<Triangle>& faces) {
  SurfaceMesh sm;
  for (std::size_t v = 0; v < vertices; ++v) sm.add_vertex({0, 0, 0});
  TriangleConnectivity ours(vertices, faces.size());
  std::size_t refused = 0;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const Triangle& t = faces[f];
    const bool cgal = sm.add_face(SurfaceMesh::Vertex_index(t[0]), SurfaceMesh::Vertex_index(t[1]),
                                  SurfaceMesh::Vertex_index(t[2])) != SurfaceMesh::null_face();
    EXPECT_EQ(ours.add_face(t), cgal) << "face " << f;
    refused += cgal ? 0 : 1;
  }
  const RingFaces expected = extract_rings(sm);
  const RingFaces found = ours.rings();
  EXPECT_EQ(found.offsets, expected.offsets);
  EXPECT_EQ(found.source, expected.source);
  EXPECT_EQ(found.face, expected.face);
  EXPECT_EQ(found.opposite_face, expected.opposite_face);
  return refused;
}

std::vector<Triangle> grid_faces(int n) {
  std::vector<Triangle> faces;
  const auto at = [n](int i, int j) { return static_cast<std::uint32_t>(i * n + j); };
  for (int i = 0; i + 1 < n; ++i) {
    for (int j = 0; j + 1 < n; ++j) {
      faces.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      faces.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  return faces;
}

TEST(TriangleConnectivity, ClosedMeshesInFileOrderAndShuffled) {
  std::mt19937 rng(3);
  for (const char* name : {"cmdm/blob4_ref.off", "cmdm/monkey2.obj"}) {
    SCOPED_TRACE(name);
    const ColoredMesh mesh = read_mesh(test::reference_dir() / name).mesh;
    EXPECT_EQ(expect_same_as_cgal(mesh.positions.size(), mesh.triangles), 0u);
    std::vector<Triangle> shuffled = mesh.triangles;
    std::shuffle(shuffled.begin(), shuffled.end(), rng);
    expect_same_as_cgal(mesh.positions.size(), shuffled);
  }
}

TEST(TriangleConnectivity, MeshWithBordersInEveryOrder) {
  std::mt19937 rng(5);
  std::vector<Triangle> faces = grid_faces(30);
  EXPECT_EQ(expect_same_as_cgal(900, faces), 0u);
  std::reverse(faces.begin(), faces.end());
  EXPECT_EQ(expect_same_as_cgal(900, faces), 0u);
  for (int k = 0; k < 5; ++k) {
    std::shuffle(faces.begin(), faces.end(), rng);
    expect_same_as_cgal(900, faces);
  }
}

TEST(TriangleConnectivity, NonManifoldSoupsAreRefusedFaceForFace) {
  std::mt19937 rng(9);
  std::size_t refused = 0;
  for (int k = 0; k < 20; ++k) {
    // Random triangles over few vertices: shared edges, fans meeting at one vertex, edges used
    // twice in the same direction, repeated vertices.
    const std::uint32_t vertices = 12 + 4 * k;
    std::uniform_int_distribution<std::uint32_t> v(0, vertices - 1);
    std::vector<Triangle> faces(3 * vertices);
    for (Triangle& t : faces) t = {v(rng), v(rng), v(rng)};
    refused += expect_same_as_cgal(vertices, faces);
    // A grid with a few faces duplicated, flipped or pinched onto one vertex.
    std::vector<Triangle> grid = grid_faces(8);
    for (int j = 0; j < 6; ++j) {
      Triangle t = grid[v(rng) % grid.size()];
      if (j % 3 == 1) std::swap(t[0], t[1]);
      if (j % 3 == 2) t[2] = v(rng) % 64;
      grid.push_back(t);
    }
    std::shuffle(grid.begin(), grid.end(), rng);
    refused += expect_same_as_cgal(64, grid);
  }
  EXPECT_GT(refused, 100u);  // the refusal paths were exercised
}

}  // namespace
}  // namespace qm3d::mesh::detail
