// The curvature estimate next to degenerate geometry (curvature.h, dihedral.h): CMDM repairs
// the normal of a zero-area face, MSDM2 gives the vertices whose ball reaches it curvature 0
// (SPEC-CMDM 1.5 step 4 and §MSDM2-degenerate).
#include "curvature.h"

#include <gtest/gtest.h>

#include <cmath>

#include "multiscale.h"

namespace qm3d::mesh::detail {
namespace {

// A fan of four faces around M, one of them (A, M, B) collinear, so its normal is NaN, plus one
// face (A, B, C) on the other side of AB:
//
//        D       E
//         \     /
//    A --- M --- B
//         \  /
//          C
enum Vertex : std::uint32_t { A, M, B, C, D, E };

ColoredMesh fan_with_collinear_face() {
  ColoredMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {1, -1, 0.4}, {0.5, 1, -0.2}, {1.5, 1, 0.5}};
  mesh.triangles = {{A, M, B}, {B, M, E}, {E, M, D}, {D, M, A}, {A, B, C}};
  return mesh;
}

std::vector<double> curvature_as_in(const MultiscaleDefinition& def, const ColoredMesh& input,
                                    double radius) {
  const HalfedgeMesh mesh = build_halfedge_mesh(input, "fan", def.degenerate_edges, 1);
  return processed_curvature(mesh, radius, /*maxdim=*/1.0, def.curvature, 1);
}

TEST(Curvature, FaceNormalIsNanExactlyWhereMeppsIs) {
  // Three nearly collinear points: MEPP2's (c - b) x (a - b) for face (a, b, c) is tiny but not
  // zero, while the same triangle started at c, (b - a) x (c - a), rounds to exactly zero.
  const Vec3 a{0.1, -0.4, 0.0}, b{0.07, -0.39, -0.1}, c{0.010000000000000009, -0.37, -0.3};
  EXPECT_EQ(face_normal(a, b, c), (Vec3{0, 1, 0}));
  EXPECT_TRUE(std::isnan(face_normal(c, a, b)[0]));
}

TEST(Curvature, Msdm2GivesZeroNextToAZeroAreaFace) {
  const ColoredMesh fan = fan_with_collinear_face();
  // A radius smaller than every edge: each vertex sees only its own edges.
  const auto curv = curvature_as_in(kMsdm2Definition, fan, 0.1);
  EXPECT_EQ(curv[M], 0.0);  // MA and MB border the collinear face
  EXPECT_EQ(curv[A], 0.0);  // AM, AB too
  EXPECT_EQ(curv[B], 0.0);
  EXPECT_GT(curv[D], 0.0);  // DM is between two regular faces; DA and DE are border edges
  EXPECT_GT(curv[E], 0.0);
  // A ball that reaches M from D through DM takes in MA and MB as well.
  EXPECT_EQ(curvature_as_in(kMsdm2Definition, fan, 1.5)[D], 0.0);
}

TEST(Curvature, CmdmRepairsTheNormalOfAZeroAreaFace) {
  const ColoredMesh fan = fan_with_collinear_face();
  const auto curv = curvature_as_in(kCmdmDefinition, fan, 0.1);
  EXPECT_GT(curv[M], 0.0);
  EXPECT_GT(curv[D], 0.0);
  EXPECT_TRUE(std::isfinite(curv[M]));
  // Only the rule for degenerate edges differs: MSDM2's tensor with CMDM's repair is not zero.
  MultiscaleDefinition repaired = kMsdm2Definition;
  repaired.degenerate_edges = DegenerateEdges::kRepaired;
  EXPECT_GT(curvature_as_in(repaired, fan, 0.1)[M], 0.0);
}

}  // namespace
}  // namespace qm3d::mesh::detail
