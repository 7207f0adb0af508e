#include "qm3d/mesh/cmdm.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "disposable_inputs.h"
#include "qm3d/common/error.h"
#include "progress_recorder.h"
#include "qm3d/mesh/mesh_io.h"
#include "qm3d/mesh/msdm2.h"
#include "test_paths.h"

namespace qm3d::mesh {
namespace {

std::filesystem::path cmdm_dir() { return test::reference_dir() / "cmdm"; }
std::filesystem::path quantised_dir() { return test::reference_dir() / "quantised"; }

// A reference mesh by file name: the quantised copies of blob5 are in quantised/, every other
// mesh (blob5_ref.off included) is in cmdm/.
std::filesystem::path mesh_path(const std::string& name) {
  const auto quantised = quantised_dir() / name;
  return std::filesystem::exists(quantised) ? quantised : cmdm_dir() / name;
}

struct ReferenceRow {
  std::string ref, dist;
  double sym, d2r, r2d, bb_d2r, bb_r2d;
  FeatureVector f_d2r, f_r2d;
};

std::vector<ReferenceRow> reference_rows(const std::filesystem::path& table) {
  std::ifstream in(table);
  std::string line;
  std::getline(in, line);  // header
  std::vector<ReferenceRow> rows;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    ReferenceRow r;
    s >> r.ref >> r.dist >> r.sym >> r.d2r >> r.r2d >> r.bb_d2r >> r.bb_r2d;
    for (double& f : r.f_d2r) s >> f;
    for (double& f : r.f_r2d) s >> f;
    if (s) rows.push_back(r);
  }
  return rows;
}

// Each reference pair is computed once and shared by the tests.
const MetricResult& result_for(const std::string& ref, const std::string& dist) {
  static std::map<std::string, MetricResult> cache;
  const std::string key = ref + "|" + dist;
  auto it = cache.find(key);
  if (it == cache.end()) {
    const auto r = read_mesh(mesh_path(ref)).mesh;
    const auto d = read_mesh(mesh_path(dist)).mesh;
    it = cache.emplace(key, compute_cmdm(r, d)).first;
  }
  return it->second;
}

void expect_score(double actual, double expected, const char* what) {
  if (std::fabs(expected) < 1e-12) {
    EXPECT_NEAR(actual, expected, 1e-12) << what;
  } else {
    EXPECT_NEAR(actual, expected, 1e-6 * std::fabs(expected)) << what;
  }
}

void expect_direction(const DirectionResult& d, double score, double bb,
                      const FeatureVector& f) {
  expect_score(d.score, score, "score");
  EXPECT_NEAR(d.box_size, bb, 1e-9);
  for (std::size_t k = 0; k < kNumFeatures; ++k) EXPECT_NEAR(d.features[k], f[k], 1e-6) << "f" << k + 1;
}

void expect_rows(const std::filesystem::path& table, std::size_t count) {
  const auto rows = reference_rows(table);
  ASSERT_EQ(rows.size(), count);
  for (const auto& row : rows) {
    SCOPED_TRACE(row.ref + " vs " + row.dist);
    const MetricResult& r = result_for(row.ref, row.dist);
    expect_score(r.score, row.sym, "symmetric");
    ASSERT_TRUE(r.dist_to_ref && r.ref_to_dist);
    expect_direction(*r.dist_to_ref, row.d2r, row.bb_d2r, row.f_d2r);
    expect_direction(*r.ref_to_dist, row.r2d, row.bb_r2d, row.f_r2d);
  }
}

TEST(Cmdm, MatchesEveryReferenceRow) { expect_rows(cmdm_dir() / "cmdm_reference.tsv", 8); }

// blob5 quantised to 6, 8 and 10 bits: zero-area faces and coincident vertices (6 bits), where
// CMDM's curvature uses replacement normals (SPEC-CMDM 1.5 step 4).
TEST(Cmdm, MatchesEveryQuantisedReferenceRow) {
  expect_rows(quantised_dir() / "cmdm_quantised_reference.tsv", 4);
}

// LD per vertex in both directions against `stem`_LD_dist.txt / _LD_ref.txt in `dir`/per_vertex.
void expect_per_vertex(const std::string& ref, const std::string& dist,
                       const std::filesystem::path& dir, const std::string& stem) {
  const MetricResult& r = result_for(ref, dist);
  const auto ld_dist = test::read_column(dir / "per_vertex" / (stem + "_LD_dist.txt"));
  const auto ld_ref = test::read_column(dir / "per_vertex" / (stem + "_LD_ref.txt"));
  ASSERT_EQ(r.dist_to_ref->per_element.size(), ld_dist.size());
  ASSERT_EQ(r.ref_to_dist->per_element.size(), ld_ref.size());
  double worst = 0;
  for (std::size_t i = 0; i < ld_dist.size(); ++i) {
    worst = std::max(worst, std::fabs(r.dist_to_ref->per_element[i] - ld_dist[i]));
  }
  for (std::size_t i = 0; i < ld_ref.size(); ++i) {
    worst = std::max(worst, std::fabs(r.ref_to_dist->per_element[i] - ld_ref[i]));
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(Cmdm, PerVertexMatchesMonkey) {
  expect_per_vertex("monkey2.obj", "monkey_simplified.obj", cmdm_dir(),
                    "LD_monkey_simplified_vs_monkey2");
}

TEST(Cmdm, PerVertexMatchesBlob4BothNoise) {
  expect_per_vertex("blob4_ref.off", "blob4_bothnoise.off", cmdm_dir(),
                    "LD_blob4_bothnoise_vs_blob4_ref");
}

TEST(Cmdm, PerVertexMatchesQuantised) {
  for (const std::string bits : {"6", "8"}) {
    SCOPED_TRACE(bits + " bits");
    expect_per_vertex("blob5_ref.off", "blob5_pquant" + bits + ".off", quantised_dir(),
                      "LD_blob5_pquant" + bits + "_vs_blob5_ref");
  }
}

TEST(Cmdm, ObjOffAndPlyCopiesGiveTheSameScore) {
  const double off = result_for("blob4_ref.off", "blob4_bothnoise.off").score;
  EXPECT_NEAR(result_for("blob4_ref.obj", "blob4_bothnoise.obj").score, off, 1e-9);
  EXPECT_EQ(result_for("blob4_ref.ply", "blob4_bothnoise.ply").score, off);
}

TEST(Cmdm, OneAndTwoThreadsAreBitIdentical) {
  const auto r = read_mesh(cmdm_dir() / "monkey2.obj").mesh;
  const auto d = read_mesh(cmdm_dir() / "monkey_simplified.obj").mesh;
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const MetricResult one = compute_cmdm(r, d);
  omp_set_num_threads(2);
  const MetricResult two = compute_cmdm(r, d);
  omp_set_num_threads(saved);
  EXPECT_EQ(one.score, two.score);
  EXPECT_EQ(one.dist_to_ref->features, two.dist_to_ref->features);
  EXPECT_EQ(one.ref_to_dist->per_element, two.ref_to_dist->per_element);
}

// The threads option reaches every parallel part, the concurrent preparation and matching
// included (one thread: nothing runs concurrently); the result never depends on it.
TEST(Cmdm, ThreadsOptionGivesBitIdenticalResults) {
  const auto r = read_mesh(cmdm_dir() / "blob4_ref.off").mesh;
  const auto d = read_mesh(cmdm_dir() / "blob4_bothnoise.off").mesh;
  CmdmOptions o;
  o.threads = 1;
  const MetricResult one = compute_cmdm(r, d, o);
  for (int threads : {2, 3}) {
    o.threads = threads;
    const MetricResult many = compute_cmdm(r, d, o);
    EXPECT_EQ(one.score, many.score) << threads;
    EXPECT_EQ(one.ref_to_dist->features, many.ref_to_dist->features) << threads;
    EXPECT_EQ(one.dist_to_ref->per_element, many.dist_to_ref->per_element) << threads;
  }
}

TEST(Cmdm, DirectionOptionComputesOnlyWhatIsAsked) {
  const auto r = read_mesh(cmdm_dir() / "monkey2.obj").mesh;
  const auto d = read_mesh(cmdm_dir() / "monkey_simplified.obj").mesh;
  CmdmOptions o;
  o.direction = Direction::kDistToRef;
  const MetricResult one = compute_cmdm(r, d, o);
  EXPECT_TRUE(one.dist_to_ref);
  EXPECT_FALSE(one.ref_to_dist);
  EXPECT_EQ(one.score, result_for("monkey2.obj", "monkey_simplified.obj").dist_to_ref->score);
}

// Fractions start at 0, never decrease and end at 1; the stages name the direction and scale.
void expect_sound_progress(const test::ProgressCalls& calls,
                           const std::string& some_stage) {
  ASSERT_GE(calls.size(), 2u);
  EXPECT_EQ(calls.front().second, 0.0);
  EXPECT_EQ(calls.back(), std::make_pair(std::string("done"), 1.0));
  bool seen = false;
  for (std::size_t i = 0; i < calls.size(); ++i) {
    if (i > 0) {
      EXPECT_LE(calls[i - 1].second, calls[i].second) << calls[i].first;
    }
    EXPECT_LE(calls[i].second, 1.0);
    seen = seen || calls[i].first == some_stage;
  }
  EXPECT_TRUE(seen) << some_stage;
}

TEST(Cmdm, ReportsProgressWithoutChangingTheResult) {
  const auto r = read_mesh(cmdm_dir() / "blob4_ref.off").mesh;
  const auto d = read_mesh(cmdm_dir() / "blob4_bothnoise.off").mesh;
  test::ProgressRecorder recorder;
  const test::ProgressCalls& calls = recorder.calls;
  CmdmOptions o;
  o.progress = recorder.callback();
  const MetricResult with = compute_cmdm(r, d, o);
  expect_sound_progress(calls, "ref→dist: neighbourhoods, scales 1-3");
  // connectivity, matching, 2 x (the curvatures and the neighbourhoods of all scales), done
  EXPECT_EQ(recorder.stage_starts().size(), 2u + 2 * 2 + 1);
  EXPECT_EQ(with.score, compute_cmdm(r, d).score);
  // Issue 44 item 6: the walks report from inside their loop, every hundredth of the vertices
  // the calling thread sees. On one thread it sees them all, so the count is certain (on more,
  // the other threads may take most of the loop on a loaded machine).
  recorder.calls.clear();
  o.threads = 1;
  EXPECT_EQ(compute_cmdm(r, d, o).score, with.score);
  for (const char* stage : {"ref→dist: neighbourhoods, scales 1-3", "ref→dist: curvature, scales 1-3"}) {
    EXPECT_GE(recorder.within(stage).size(), 50u) << stage;
    EXPECT_LE(recorder.within(stage).size(), 1000u) << stage;
  }
  o.threads = 0;
  recorder.calls.clear();
  o.direction = Direction::kDistToRef;
  compute_cmdm(r, d, o);
  expect_sound_progress(calls, "dist→ref: closest points");
}

// More scales than one walk serves (8): the walks come in chunks, "scales 1-8 of 10" then
// "scales 9-10 of 10", the radii going on growing across the chunk; the 9th and 10th scales
// count (the score is not the 8 scales' one) and the result does not depend on the threads.
TEST(Cmdm, MoreScalesThanOneWalkServesComeInChunks) {
  const auto r = read_mesh(cmdm_dir() / "blob4_ref.off").mesh;
  const auto d = read_mesh(cmdm_dir() / "blob4_bothnoise.off").mesh;
  test::ProgressRecorder recorder;
  CmdmOptions o;
  o.scales = 10;
  o.threads = 2;
  o.direction = Direction::kDistToRef;
  o.progress = recorder.callback();
  const MetricResult ten = compute_cmdm(r, d, o);
  std::vector<std::string> stages;
  for (const auto& call : recorder.stage_starts()) stages.push_back(call.first);
  EXPECT_EQ(stages, (std::vector<std::string>{"connectivity", "dist→ref: closest points",
                                              "dist→ref: curvature, scales 1-8 of 10",
                                              "dist→ref: neighbourhoods, scales 1-8 of 10",
                                              "dist→ref: curvature, scales 9-10 of 10",
                                              "dist→ref: neighbourhoods, scales 9-10 of 10",
                                              "done"}));
  ASSERT_TRUE(std::isfinite(ten.score));
  o.progress = nullptr;
  o.scales = 8;
  EXPECT_NE(compute_cmdm(r, d, o).score, ten.score);
  o.scales = 10;
  o.threads = 1;
  EXPECT_EQ(compute_cmdm(r, d, o).score, ten.score);
}

// The caller may free both meshes once inputs_done is called: the metric reads them no more
// (they are emptied here; reading them afterwards would change the result or fail under the
// sanitizers).
TEST(Cmdm, InputsDoneComesOnceAndTheMeshesAreNotReadAfterIt) {
  const auto r = read_mesh(cmdm_dir() / "blob4_ref.off").mesh;
  const auto d = read_mesh(cmdm_dir() / "blob4_bothnoise.off").mesh;
  for (int threads : {1, 2}) {
    CmdmOptions o;
    o.threads = threads;
    const MetricResult expected = compute_cmdm(r, d, o);
    test::DisposableInputs<ColoredMesh> inputs{r, d};
    o.inputs_done = inputs.callback();
    const MetricResult got = compute_cmdm(inputs.reference, inputs.distorted, o);
    EXPECT_EQ(inputs.calls, 1) << threads;
    EXPECT_EQ(got.score, expected.score) << threads;
    EXPECT_EQ(got.dist_to_ref->per_element, expected.dist_to_ref->per_element) << threads;
    EXPECT_EQ(got.ref_to_dist->per_element, expected.ref_to_dist->per_element) << threads;
    EXPECT_EQ(got.warnings, expected.warnings) << threads;
  }
}

TEST(Cmdm, ScoreGrowsWithColourNoise) {
  const double col = result_for("blob4_ref.off", "blob4_colnoise.off").score;
  const double both = result_for("blob4_ref.off", "blob4_bothnoise.off").score;
  const double same = result_for("blob4_ref.off", "blob4_ref.off").score;
  EXPECT_LT(same, 1e-12);
  EXPECT_GT(col, 100 * same);
  EXPECT_GT(both, col);
}

TEST(Cmdm, WeightsAndScalesAreOptions) {
  const auto r = read_mesh(cmdm_dir() / "blob4_ref.off").mesh;
  const auto d = read_mesh(cmdm_dir() / "blob4_colnoise.off").mesh;
  CmdmOptions o;
  o.model = cmdm_model();
  o.model->weights = {0, 0, 0, 0, 0, 0, 1, 0};  // chroma only
  o.direction = Direction::kDistToRef;
  const MetricResult chroma_only = compute_cmdm(r, d, o);
  EXPECT_DOUBLE_EQ(chroma_only.score, chroma_only.dist_to_ref->features[6]);
  o.scales = 1;
  EXPECT_NE(compute_cmdm(r, d, o).score, chroma_only.score);
  o.scales = 0;
  EXPECT_THROW(compute_cmdm(r, d, o), std::invalid_argument);
}

TEST(Cmdm, ZeroSizeMeshIsANumericError) {
  ColoredMesh flat{{{1, 1, 1}, {1, 1, 1}, {1, 1, 1}}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 1, 2}}};
  EXPECT_THROW(compute_cmdm(flat, flat), NumericError);
}

// A mesh built in memory is not checked by a reader: a NaN coordinate is an error naming the
// vertex, in either mesh and for MSDM2 too (the search trees need ordered coordinates).
TEST(Cmdm, NonFiniteCoordinateGivenInMemoryIsAFormatError) {
  const ColoredMesh good = read_mesh(mesh_path("blob4_ref.off")).mesh;
  ColoredMesh bad = good;
  bad.positions[7][1] = std::numeric_limits<double>::quiet_NaN();
  const ColoredMesh& bad_ref = bad;
  for (const auto& [a, b] : {std::pair{&good, &bad_ref}, std::pair{&bad_ref, &good}}) {
    try {
      compute_cmdm(*a, *b);
      ADD_FAILURE() << "no error";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find("vertex 7 has a non-finite coordinate"), std::string::npos)
          << e.what();
    }
  }
  bad.positions[7][1] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(compute_msdm2(good, bad), FormatError);
}

}  // namespace
}  // namespace qm3d::mesh
