#include "qm3d/mesh/msdm2.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "progress_recorder.h"
#include "qm3d/mesh/mesh_io.h"
#include "test_paths.h"

namespace qm3d::mesh {
namespace {

std::filesystem::path cmdm_dir() { return test::reference_dir() / "cmdm"; }

TEST(Msdm2, MatchesEveryReferenceRow) {
  std::ifstream in(test::reference_dir() / "msdm2" / "msdm2_reference.tsv");
  std::string line;
  std::getline(in, line);  // header
  int rows = 0;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string ref, dist;
    double expected = 0;
    s >> ref >> dist >> expected;
    SCOPED_TRACE(ref + " vs " + dist);
    const auto r = read_mesh(cmdm_dir() / ref).mesh;
    const auto d = read_mesh(cmdm_dir() / dist).mesh;
    const MeshMetricResult m = compute_msdm2(r, d);
    // The reference printed 6 significant digits. On blob4_geonoise / bothnoise ~13% of the
    // distorted vertices project onto an edge of the reference, equidistant from two faces, and
    // MSDM2 measures its Heron distances from the off-surface vertex: these rows only match when
    // the AABB tree reports the same face as MEPP2's (its hints built before the tree, in face
    // order); other hints move the score by 6e-5.
    EXPECT_NEAR(m.score, expected, 1e-5 * expected);
    ASSERT_TRUE(m.dist_to_ref);
    EXPECT_FALSE(m.ref_to_dist);
    ++rows;
  }
  EXPECT_EQ(rows, 4);
}

TEST(Msdm2, IdenticalMeshesGiveZero) {
  const auto r = read_mesh(cmdm_dir() / "blob4_ref.off").mesh;
  Msdm2Options o;
  o.direction = Direction::kSymmetric;
  const MeshMetricResult m = compute_msdm2(r, r, o);
  EXPECT_LT(m.score, 1e-12);
  EXPECT_TRUE(m.dist_to_ref && m.ref_to_dist);
}

// blob4_ref and its geometric-noise version.
class Msdm2Blob4 : public ::testing::Test {
 protected:
  ColoredMesh ref_ = read_mesh(cmdm_dir() / "blob4_ref.off").mesh;
  ColoredMesh geonoise_ = read_mesh(cmdm_dir() / "blob4_geonoise.off").mesh;
};

TEST_F(Msdm2Blob4, IgnoresColourAndWorksWithoutIt) {
  ColoredMesh r = ref_, d = geonoise_;
  const double with_color = compute_msdm2(r, d).score;
  r.colors.clear();
  d.colors.clear();
  EXPECT_EQ(compute_msdm2(r, d).score, with_color);
  EXPECT_EQ(compute_msdm2(r, read_mesh(cmdm_dir() / "blob4_colnoise.off").mesh).score,
            compute_msdm2(r, r).score);
}

TEST_F(Msdm2Blob4, LocalDistortionPoolsToTheScore) {
  const MeshMetricResult m = compute_msdm2(ref_, geonoise_);
  double sum = 0;
  for (double ld : m.dist_to_ref->local_distortion) sum += ld * ld * ld;
  EXPECT_NEAR(std::cbrt(sum / m.dist_to_ref->local_distortion.size()), m.score, 1e-12);
  EXPECT_EQ(m.dist_to_ref->local_distortion.size(), geonoise_.num_vertices());
}

TEST_F(Msdm2Blob4, ReportsEachScaleOfItsDirection) {
  test::ProgressRecorder recorder;
  Msdm2Options o;
  o.progress = recorder.callback();
  EXPECT_EQ(compute_msdm2(ref_, geonoise_, o).score, compute_msdm2(ref_, geonoise_).score);
  EXPECT_EQ(recorder.calls, (test::ProgressCalls{{"connectivity", 0.0},
                                                 {"dist→ref: closest points", 0.2},
                                                 {"dist→ref: scale 1/3", 0.4},
                                                 {"dist→ref: scale 2/3", 0.6},
                                                 {"dist→ref: scale 3/3", 0.8},
                                                 {"done", 1.0}}));
}

}  // namespace
}  // namespace qm3d::mesh
