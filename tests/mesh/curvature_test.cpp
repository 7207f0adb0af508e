// The curvature estimate next to degenerate geometry (curvature.h, dihedral.h): CMDM repairs
// the normal of a zero-area face, MSDM2 gives the vertices whose ball reaches it curvature 0
// (SPEC-CMDM 1.5 step 4 and §MSDM2-degenerate).
#include "curvature.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>

#include "multiscale.h"
#include "qm3d/mesh/mesh_io.h"
#include "test_paths.h"

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

// One walk for several radii (processed_curvatures) against one walk per radius
// (processed_curvature, MEPP2's as written): the same edges contribute at each radius, summed in
// another order, so the values agree to rounding of the tensor, as amplified by the eigenvalues
// (at most `tolerance` times the largest curvature of the mesh at that radius).
void expect_same_curvatures(const HalfedgeMesh& mesh, const std::vector<double>& radii,
                            CurvatureVariant variant, double maxdim, double tolerance) {
  const auto together = processed_curvatures(mesh, radii, maxdim, variant, 2);
  ASSERT_EQ(together.size(), radii.size());
  for (std::size_t j = 0; j < radii.size(); ++j) {
    const auto alone = processed_curvature(mesh, radii[j], maxdim, variant, 1);
    ASSERT_EQ(together[j].size(), alone.size());
    double largest = 0;
    for (double c : alone) largest = std::max(largest, std::fabs(c));
    double worst = 0;
    std::size_t at = 0, differ = 0, zeros = 0;
    for (std::size_t v = 0; v < alone.size(); ++v) {
      const double diff = std::fabs(together[j][v] - alone[v]);
      differ += diff != 0;
      zeros += alone[v] == 0;
      if (diff > worst) worst = diff, at = v;
    }
    EXPECT_LE(worst, tolerance * largest) << "radius " << radii[j] << ", vertex " << at << ": "
                                          << alone[at] << " vs " << together[j][at];
  }
}

TEST(Curvature, OneWalkGivesEachRadiusItsOwnCurvature) {
  // On blob4 the values differ by at most 3e-15 of the largest. On blob5 quantised to 6 bits
  // by up to 3e-9 of it: the closed-form eigenvalues (computeDirect, post_process) of tensors
  // with nearly repeated eigenvalues amplify the rounding of the reordered sums (measured with
  // Eigen's iterative solver instead: at most 1.1e-15 of the largest, on both meshes).
  for (const auto& [file, tolerance] : {std::pair{"cmdm/blob4_bothnoise.off", 1e-14},
                                        std::pair{"quantised/blob5_pquant6.off", 1e-8}}) {
    SCOPED_TRACE(file);
    const ColoredMesh input = read_mesh(test::reference_dir() / file).mesh;
    for (const MultiscaleDefinition* def : {&kCmdmDefinition, &kMsdm2Definition}) {
      const HalfedgeMesh mesh = build_halfedge_mesh(input, file, def->degenerate_edges, 1);
      // Edges about 0.07 long (blob4: a sphere of radius 1): balls of one to a few rings, in
      // CMDM's and MSDM2's ratios, and a repeated radius.
      expect_same_curvatures(mesh, {0.04, 0.06, 0.08}, def->curvature, 2.0, tolerance);
      expect_same_curvatures(mesh, {0.05, 0.05, 0.1, 0.2}, def->curvature, 2.0, tolerance);
    }
  }
}

TEST(Curvature, OneWalkKeepsMsdm2sZeroAtTheRadiiThatReachAZeroAreaFace) {
  const ColoredMesh fan = fan_with_collinear_face();
  const HalfedgeMesh mesh = build_halfedge_mesh(fan, "fan", kMsdm2Definition.degenerate_edges, 1);
  const auto curv = processed_curvatures(mesh, {0.1, 1.5}, 1.0, kMsdm2Definition.curvature, 1);
  EXPECT_GT(curv[0][D], 0.0);  // D's own edges only
  EXPECT_EQ(curv[1][D], 0.0);  // the ball reaches M through DM and takes in MA and MB
  for (std::size_t v = 0; v < fan.positions.size(); ++v) {
    EXPECT_EQ(curv[0][v], curvature_as_in(kMsdm2Definition, fan, 0.1)[v]) << v;
    EXPECT_EQ(curv[1][v], curvature_as_in(kMsdm2Definition, fan, 1.5)[v]) << v;
  }
  EXPECT_THROW(processed_curvatures(mesh, {0.2, 0.1}, 1.0, kMsdm2Definition.curvature, 1),
               std::invalid_argument);
}

}  // namespace
}  // namespace qm3d::mesh::detail
