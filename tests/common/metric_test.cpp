// The metric registry's machinery (qm3d/common/metric.h) with metrics and inputs made here: format
// recognition by content, option checking, applicability, and what run_metric adds.
#include "qm3d/common/metric.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "qm3d/common/error.h"

namespace qm3d {
namespace {

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(DetectFormat, RecognisesEachFormatByContent) {
  EXPECT_EQ(detect_format("ply\nformat ascii 1.0\n", "a"), FileFormat::kPly);
  EXPECT_EQ(detect_format("ply\r\nformat ascii 1.0\r\n", "a"), FileFormat::kPly);
  EXPECT_EQ(detect_format("OFF\n3 1 0\n", "a"), FileFormat::kOff);
  EXPECT_EQ(detect_format("# comment\nCOFF\n3 1 0\n", "a"), FileFormat::kOff);
  EXPECT_EQ(detect_format("NOFF 3 1 0\n", "a"), FileFormat::kOff);
  EXPECT_EQ(detect_format("# .PCD v0.7\nVERSION 0.7\n", "a"), FileFormat::kPcd);
  EXPECT_EQ(detect_format("VERSION .7\nFIELDS x y z\n", "a"), FileFormat::kPcd);
  EXPECT_EQ(detect_format("# made by hand\nv 0 0 0\nv 1 0 0\n", "a"), FileFormat::kObj);
  EXPECT_EQ(detect_format("mtllib a.mtl\n  v 0 0 0\n", "a"), FileFormat::kObj);
  EXPECT_NE(error_of([] {
              detect_format("solid x\nfacet\n", "x.stl");
            }).find("x.stl: not a PLY, OBJ, OFF or PCD file"),
            std::string::npos);
  EXPECT_THROW(detect_format(std::string("v 0 0 0\0\1", 9), "bin"), FormatError);
  EXPECT_THROW(detect_format("MOFF\n", "m"), FormatError);  // not an OFF keyword
}

TEST(DetectFormat, FilesFallBackToTheirExtensionOnlyWhenTheContentSaysNothing) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("qm3d_detect_format_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto write = [&](const char* name, const std::string& text) {
    std::ofstream(dir / name, std::ios::binary) << text;
    return dir / name;
  };
  EXPECT_EQ(detect_format(write("cloud.dat", "ply\nformat ascii 1.0\nend_header\n")),
            FileFormat::kPly);
  EXPECT_EQ(detect_format(write("mesh.ply", "OFF\n3 1 0\n")), FileFormat::kOff);
  EXPECT_EQ(detect_format(write("empty.off", "")), FileFormat::kOff);  // the OFF reader says why
  EXPECT_NE(
      error_of([&] { detect_format(write("x.stl", "solid x\n")); }).find("unknown format '.stl'"),
      std::string::npos);
  EXPECT_THROW(detect_format(dir / "missing.ply"), InputError);
  EXPECT_THROW(detect_format(dir), InputError);
  std::filesystem::remove_all(dir);
}

TEST(Input, RecognisesLargeFilesFromTheirHead) {
  // More than the 1 MiB looked at: the declared counts are checked against the file's size.
  const auto path = std::filesystem::temp_directory_path() /
                    ("qm3d_large_cloud_" + std::to_string(::getpid()) + ".ply");
  const std::size_t n = 100000;
  std::string bytes = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(n) +
                      "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  bytes.resize(bytes.size() + n * 12, '\0');
  std::ofstream(path, std::ios::binary) << bytes;
  const Registry reg;
  const Input in = Input::from_file(path, reg);
  EXPECT_FALSE(in.is_mesh());
  EXPECT_EQ(in.format(), FileFormat::kPly);
  std::filesystem::resize_file(path, bytes.size() - 12);  // one point short
  EXPECT_THROW(Input::from_file(path, reg), FormatError);
  std::filesystem::remove(path);
}

// A metric made here: the score is the difference of the first coordinates' sums.
MetricSpec toy_metric(const std::string& name, AppliesTo applies) {
  MetricSpec s;
  s.name = name;
  s.title = name;
  s.applies_to = applies;
  s.reads = Input::Kind::kCloud;
  s.default_direction = Direction::kRefToDist;
  s.options = {{"scale", "a factor", 1.0, {}, 0, 10, true},
               {"count", "an integer", 3, {}, 1, 5},
               {"mode", "a choice", "a", {"a", "b"}},
               {"flag", "a flag", false, {}},
               {"weights", "three numbers", {1.0, 2.0, 3.0}, {}}};
  s.run = [](const MetricSpec& spec, const Input& ref, const Input& dist, const RunOptions&,
             const OptionValues& v) {
    double a = 0, b = 0;
    for (const auto& p : ref.cloud().positions) a += p[0];
    for (const auto& p : dist.cloud().positions) b += p[0];
    if (v.at("mode") == "b") throw NumericError("mode b cannot be computed");
    MetricResult r;
    r.metric = spec.name;
    r.ref_to_dist = DirectionResult{v.at("scale").get<double>() * (b - a), {}, 1, {}};
    combine_directions(r);
    return r;
  };
  return s;
}

ColoredCloud cloud_of(std::initializer_list<double> xs) {
  ColoredCloud c;
  for (double x : xs) {
    c.positions.push_back({x, 0, 0});
    c.colors.push_back({0.5, 0.5, 0.5});
  }
  return c;
}

ColoredMesh triangle() {
  return ColoredMesh{
      {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 1, 2}}};
}

TEST(MetricSpec, CompleteFillsDefaultsAndRejectsWhatDoesNotFit) {
  const MetricSpec s = toy_metric("toy", AppliesTo::kBoth);
  const OptionValues d = s.complete({});
  EXPECT_EQ(d.at("scale"), 1.0);
  EXPECT_EQ(d.at("count"), 3);
  EXPECT_EQ(d.at("mode"), "a");
  EXPECT_EQ(d.at("flag"), false);
  EXPECT_EQ(s.complete({{"count", 5}, {"mode", "b"}}).at("count"), 5);
  const auto rejected = [&](const OptionValues& v, const std::string& what) {
    const std::string e = error_of([&] { s.complete(v); });
    EXPECT_NE(e.find(what), std::string::npos) << e;
  };
  rejected({{"nope", 1}}, "toy: unknown option 'nope' (known: scale, count, mode, flag, weights)");
  rejected({{"count", 6}}, "option 'count' must be <= 5 (got 6)");
  rejected({{"count", 2.5}}, "option 'count' must be an integer");
  rejected({{"scale", 0.0}}, "option 'scale' must be > 0");
  rejected({{"scale", "x"}}, "must be a number");
  rejected({{"mode", "c"}}, "must be one of a, b");
  rejected({{"flag", 1}}, "must be true or false");
  rejected({{"weights", {1.0, 2.0}}}, "must be a list of 3 numbers");
  EXPECT_THROW(s.complete(nlohmann::json::array()), std::invalid_argument);
}

TEST(Registry, FindsAppliesAndChoosesInRegistrationOrder) {
  Registry reg;
  reg.add(toy_metric("meshes_only", AppliesTo::kMeshes));
  reg.add(toy_metric("anything", AppliesTo::kBoth));
  reg.add(toy_metric("clouds_only", AppliesTo::kClouds));
  EXPECT_THROW(reg.add(toy_metric("anything", AppliesTo::kBoth)), std::logic_error);
  EXPECT_EQ(reg.find("nope"), nullptr);
  EXPECT_NE(error_of([&] {
              reg.get("nope");
            }).find("unknown metric 'nope' (expected meshes_only, anything, clouds_only)"),
            std::string::npos);
  const Input m1 = Input::from_mesh(triangle(), "m1"), m2 = Input::from_mesh(triangle(), "m2");
  const Input c1 = Input::from_cloud(cloud_of({0}), "c1"),
              c2 = Input::from_cloud(cloud_of({1}), "c2");
  const auto names = [&](const Input& a, const Input& b) {
    std::string out;
    for (const MetricSpec* m : reg.applicable(a, b)) out += m->name + " ";
    return out;
  };
  EXPECT_EQ(names(m1, m2), "meshes_only anything ");
  EXPECT_EQ(names(c1, c2), "anything clouds_only ");
  EXPECT_EQ(names(m1, c2), "anything ");
  EXPECT_EQ(reg.auto_metric(m1, m2).name, "meshes_only");
  EXPECT_EQ(reg.auto_metric(c1, m2).name, "anything");
  EXPECT_THROW(reg.sampler(), std::logic_error);
}

// A metric that dispatches on the pair (D_LAB) reads two meshes as meshes, any other pair as
// clouds; the others read as their spec says.
TEST(MetricSpec, ReadsForDispatchesOnThePairOnlyWhenAsked) {
  MetricSpec s = toy_metric("toy", AppliesTo::kBoth);
  const Input m = Input::from_mesh(triangle(), "m"), c = Input::from_cloud(cloud_of({0}), "c");
  EXPECT_EQ(s.reads_for(m, m), Input::Kind::kCloud);
  s.reads_two_meshes_as_meshes = true;
  EXPECT_EQ(s.reads_for(m, m), Input::Kind::kMesh);
  EXPECT_EQ(s.reads_for(m, c), Input::Kind::kCloud);
  EXPECT_EQ(s.reads_for(c, m), Input::Kind::kCloud);
  EXPECT_EQ(s.reads_for(c, c), Input::Kind::kCloud);
  s.reads = Input::Kind::kMesh;
  s.reads_two_meshes_as_meshes = false;
  EXPECT_EQ(s.reads_for(m, m), Input::Kind::kMesh);
  EXPECT_FALSE(Registry().colour_matcher());  // none until the mesh module registers one
}

TEST(Input, InMemoryMeshesAreAlsoClouds) {
  const Input m = Input::from_mesh(triangle(), "tri");
  EXPECT_TRUE(m.is_mesh());
  EXPECT_EQ(m.cloud().positions, triangle().positions);
  EXPECT_EQ(m.mesh().mesh.triangles.size(), 1u);
  const Input c = Input::from_cloud(cloud_of({0, 1}), "pts");
  EXPECT_FALSE(c.is_mesh());
  EXPECT_NE(error_of([&] { c.mesh(); }).find("pts: a point cloud (no faces), not a mesh"),
            std::string::npos);
}

TEST(Input, ReleaseFreesWhatWasReadFromTheFileAndKeepsDataInMemory) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("qm3d_release_" + std::to_string(::getpid()) + ".ply");
  std::ofstream(path) << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                         "property float y\nproperty float z\nend_header\n0 0 0\n";
  Registry reg;
  int reads = 0;
  reg.readers().cloud = [&](const std::filesystem::path&, FileFormat, const ReadOptions&) {
    ++reads;
    return CloudData{cloud_of({double(reads)}), {}};
  };
  const Input in = Input::from_file(path, reg);
  EXPECT_EQ(in.cloud().positions[0][0], 1.0);
  EXPECT_EQ(in.cloud().positions[0][0], 1.0);  // kept
  in.release();
  EXPECT_EQ(reads, 1);
  EXPECT_EQ(in.cloud().positions[0][0], 2.0);  // read again
  const Input memory = Input::from_cloud(cloud_of({5}), "pts");
  memory.release();
  EXPECT_EQ(memory.cloud().positions[0][0], 5.0);
  std::filesystem::remove(path);
}

TEST(RunMetric, ChecksOptionsFillsProvenanceAndNamesTheInputsInErrors) {
  const MetricSpec s = toy_metric("toy", AppliesTo::kBoth);
  const Input a = Input::from_cloud(cloud_of({0, 1}), "a.ply");
  const Input b = Input::from_cloud(cloud_of({2, 3}), "b.ply");
  RunOptions run;
  const MetricResult r = run_metric(s, a, b, run, {{"scale", 0.5}});
  EXPECT_EQ(r.score, 2.0);
  EXPECT_EQ(r.provenance.reference, "a.ply");
  EXPECT_EQ(r.provenance.distorted, "b.ply");
  EXPECT_FALSE(r.provenance.version.empty());
  EXPECT_GE(r.provenance.seconds, 0.0);
  EXPECT_THROW(run_metric(s, a, b, run, {{"scale", -1.0}}), std::invalid_argument);
  const std::string e = error_of([&] { run_metric(s, a, b, run, {{"mode", "b"}}); });
  EXPECT_NE(e.find("mode b cannot be computed (reference a.ply, distorted b.ply)"),
            std::string::npos)
      << e;
  run.model = LinearModel{"toy", {}, "test"};
  EXPECT_THROW(run_metric(s, a, b, run), std::invalid_argument);  // the toy takes no model
}

// Thread counts libgomp cannot start (65536: SIGSEGV, 33000: abort) are refused up front.
TEST(RunMetric, RefusesAbsurdThreadCountsWithTheLimit) {
  const MetricSpec s = toy_metric("toy", AppliesTo::kBoth);
  const Input a = Input::from_cloud(cloud_of({0, 1}), "a.ply");
  RunOptions run;
  for (const int threads : {65536, 1000000, max_threads() + 1, -1}) {
    run.threads = threads;
    const std::string e = error_of([&] { run_metric(s, a, a, run); });
    EXPECT_EQ(e.rfind("threads: ", 0), 0u) << e;
    EXPECT_THROW(check_thread_count(threads), std::invalid_argument);
  }
  run.threads = max_threads();
  EXPECT_NO_THROW(check_thread_count(run.threads));
  EXPECT_GE(max_threads(), kMinThreadLimit);
}

TEST(RunMetric, RefusesNonFiniteWeights) {
  const MetricSpec s = toy_metric("toy", AppliesTo::kBoth);
  MetricSpec with_model = s;
  with_model.takes_model = true;
  const Input a = Input::from_cloud(cloud_of({0, 1}), "a.ply");
  RunOptions run;
  run.model = LinearModel{"toy", {1, std::nan(""), 0, 0, 0, 0, 0, 0}, "weights="};
  const std::string e = error_of([&] { run_metric(with_model, a, a, run); });
  EXPECT_EQ(e, "weights: weight 2 of 8 is nan (must be finite)");
}

// Coordinates whose squares overflow or underflow are refused before the metric runs, naming
// the input and the limit.
TEST(RunMetric, RefusesCoordinatesWhoseSquaresOverflowOrUnderflow) {
  const MetricSpec s = toy_metric("toy", AppliesTo::kBoth);
  const Input good = Input::from_cloud(cloud_of({0, 1}), "good.ply");
  const RunOptions run;
  for (const double x : {1e100, -1e300, 2e60}) {
    const Input big = Input::from_cloud(cloud_of({0, x}), "big.ply");
    const std::string e = error_of([&] { run_metric(s, good, big, run); });
    EXPECT_EQ(e.rfind("big.ply: coordinates up to ", 0), 0u) << e;
    EXPECT_NE(e.find("squared distances would overflow"), std::string::npos) << e;
    EXPECT_THROW(run_metric(s, big, good, run), NumericError);
  }
  for (const double side : {1e-100, 1e-300}) {
    const Input tiny = Input::from_cloud(cloud_of({1, 1 + side}), "tiny.ply");
    const Input tiny_at_0 = Input::from_cloud(cloud_of({0, side}), "tiny.ply");
    // 1 + 1e-100 == 1: a box of zero size, left to the metric's own check.
    EXPECT_NO_THROW(run_metric(s, good, tiny, run));
    const std::string e = error_of([&] { run_metric(s, good, tiny_at_0, run); });
    EXPECT_EQ(e.rfind("tiny.ply: the bounding box's longest side is ", 0), 0u) << e;
    EXPECT_NE(e.find("squared distances would underflow"), std::string::npos) << e;
  }
  const Input edge = Input::from_cloud(cloud_of({0, 1e60}), "edge.ply");
  EXPECT_NO_THROW(run_metric(s, good, edge, run));
  const Input small = Input::from_cloud(cloud_of({0, 1e-60}), "small.ply");
  EXPECT_NO_THROW(run_metric(s, good, small, run));
}

// A metric that computes NaN never returns it as a score; a non-finite feature its score does
// not use is a warning (the reference's pooling skips zero-weight features).
TEST(RunMetric, ANonFiniteScoreIsANumericErrorNamingTheMetricAndAnUnusedFeatureAWarning) {
  MetricSpec s = toy_metric("toy", AppliesTo::kBoth);
  s.title = "TOY";
  const Input a = Input::from_cloud(cloud_of({0, 1}), "a.ply");
  const RunOptions run;
  s.run = [](const MetricSpec&, const Input&, const Input&, const RunOptions&,
             const OptionValues&) {
    MetricResult r;
    r.feature_names = {"f1", "f2", "f3", "f4", "f5", "f6", "f7", "f8"};
    r.ref_to_dist = DirectionResult{std::nan(""), {0, 0, NAN, 0, 0, 0, 0, 0}, 1, {}};
    combine_directions(r);
    return r;
  };
  const std::string e = error_of([&] { run_metric(s, a, a, run); });
  EXPECT_EQ(e.rfind("TOY: the ref-to-dist score nan is not finite (f3 nan)", 0), 0u) << e;
  EXPECT_NE(e.find("(reference a.ply, distorted a.ply)"), std::string::npos) << e;
  s.run = [](const MetricSpec&, const Input&, const Input&, const RunOptions&,
             const OptionValues&) {
    MetricResult r;
    r.feature_names = {"f1", "f2", "f3", "f4", "f5", "f6", "f7", "f8"};
    r.dist_to_ref = DirectionResult{0.5, {0, 0, INFINITY, 0, 0, 0, 0, 0}, 1, {}};
    combine_directions(r);
    return r;
  };
  const MetricResult r = run_metric(s, a, a, run);
  EXPECT_EQ(r.score, 0.5);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_EQ(r.warnings[0].rfind("TOY: the dist-to-ref feature f3 inf is not finite", 0), 0u)
      << r.warnings[0];
}

TEST(OptionsFor, KeepsTheNamesTheMetricKnows) {
  const MetricSpec s = toy_metric("toy", AppliesTo::kBoth);
  const OptionValues all = {{"count", 2}, {"radius", 0.1}, {"mode", "b"}};
  EXPECT_EQ(options_for(s, all), (OptionValues{{"count", 2}, {"mode", "b"}}));
}

}  // namespace
}  // namespace qm3d
