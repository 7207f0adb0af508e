// The ibsm metric (qm3d/render/ibsm.h) beyond mmetric's table (ibsm_reference_test.cpp): the
// zero-error case, a mesh against its own dense samples, views where nothing is drawn, options,
// saved views, the report's view pairs, threads.
#include "qm3d/render/ibsm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "qm3d/common/error.h"
#include "qm3d/mesh/mesh_io.h"
#include "qm3d/mesh/metrics.h"
#include "qm3d/mesh/sampling.h"
#include "test_paths.h"

namespace qm3d::render {
namespace {

namespace fs = std::filesystem;

ColoredMesh monkey() {
  return mesh::read_mesh(test::reference_dir() / "cmdm" / "monkey2.obj").mesh;
}

IbsmOptions small(int views = 6, int resolution = 256) {
  IbsmOptions o;
  o.views = views;
  o.resolution = resolution;
  o.threads = 2;
  return o;
}

double value(const MetricResult& r, const std::string& name) {
  const auto v = find_value(r.values, name);
  EXPECT_TRUE(v) << name;
  return v ? *v : NAN;
}

TEST(Ibsm, IdenticalMeshesScoreMmetricsClipEverywhere) {
  const RenderModel m = mesh_model(monkey());
  const MetricResult r = compute_ibsm(m, m, small());
  for (const char* name : {"r_mse", "yuv_mse", "geo_mse", "unmatched_pixel_percentage"}) {
    EXPECT_EQ(value(r, name), 0.0) << name;
  }
  for (const char* name : {"rgb_psnr", "yuv_psnr", "geo_psnr"}) EXPECT_EQ(value(r, name), kPsnrClip);
  EXPECT_EQ(value(r, "ssim"), 1.0);
  EXPECT_NEAR(value(r, "ms_ssim"), 1.0, 1e-12);
  EXPECT_EQ(r.score, kPsnrClip);
  EXPECT_TRUE(r.warnings.empty());
}

TEST(Ibsm, AMeshAgainstItsOwnDenseSamplesScoresHigh) {
  const ColoredMesh m = monkey();
  mesh::SamplingOptions s;
  s.points = 300000;
  const RenderModel mesh = mesh_model(m);
  const RenderModel cloud = cloud_model(mesh::sample_surface(m, s));
  const MetricResult r = compute_ibsm(mesh, cloud, small(8, 512));
  // Measured 36.8 dB, SSIM 0.85, 3.8 % unmatched (the simplified monkey scores 26.8 dB in
  // mmetric's table).
  EXPECT_GT(r.score, 35.0);
  EXPECT_LT(r.score, kPsnrClip);  // never "perfect": the cloud is drawn
  std::cout << "[mesh vs samples] yuv_psnr " << r.score << " ssim " << value(r, "ssim") << " unmatched % " << value(r, "unmatched_pixel_percentage") << "\n";
  EXPECT_GT(value(r, "ssim"), 0.8);
  EXPECT_LT(value(r, "unmatched_pixel_percentage"), 5.0);
  // A coarser cloud scores lower.
  s.points = 20000;
  const MetricResult coarse = compute_ibsm(mesh, cloud_model(mesh::sample_surface(m, s)), small(8, 512));
  EXPECT_LT(coarse.score, r.score);
}

/// One triangle in the plane y = 0 facing +y: culled from below.
RenderModel one_face() {
  ColoredMesh t;
  t.positions = {{0, 0, 0}, {0, 0, 1}, {1, 0, 0}};
  t.colors = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  t.triangles = {{0, 1, 2}};
  return mesh_model(t);
}

TEST(Ibsm, AViewWhereNothingIsDrawnIsLeftOutWithAWarning) {
  // Two views: +y (the face) and -y (culled: nothing drawn).
  const RenderModel face = one_face();
  const MetricResult r = compute_ibsm(face, face, small(2, 64));
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("view 1"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[0].find("left out"), std::string::npos) << r.warnings[0];
  EXPECT_EQ(r.details.at("views_left_out").get<int>(), 1);
  EXPECT_TRUE(r.details.at("views").at(1).at("left_out").get<bool>());
  EXPECT_EQ(r.score, kPsnrClip);
}

TEST(Ibsm, NoPixelDrawnByBothIsAnError) {
  // The face against itself moved out of every view's common pixels: far away in +x.
  ColoredMesh far;
  far.positions = {{50, 0, 0}, {50, 0, 1}, {51, 0, 0}};
  far.colors = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  far.triangles = {{0, 2, 1}};  // facing -y: never seen with the other from one view
  try {
    compute_ibsm(one_face(), mesh_model(far), small(2, 64), "a.ply", "b.ply");
    FAIL() << "no error";
  } catch (const NumericError& e) {
    EXPECT_NE(std::string(e.what()).find("a.ply"), std::string::npos) << e.what();
  }
}

TEST(Ibsm, OptionsAreChecked) {
  const RenderModel face = one_face();
  IbsmOptions o = small();
  o.layout = ViewLayout::kCmdm18;
  o.views = 6;
  EXPECT_THROW(compute_ibsm(face, face, o), std::invalid_argument);
  o.views = 16;
  o.rotation_deg = {0, 0, 30};
  EXPECT_THROW(compute_ibsm(face, face, o), std::invalid_argument);
  o = small();
  o.views = 1;
  EXPECT_THROW(compute_ibsm(face, face, o), std::invalid_argument);
  o = small();
  o.resolution = 8;
  EXPECT_THROW(compute_ibsm(face, face, o), std::invalid_argument);
}

TEST(Ibsm, Cmdm18LayoutHas18Views) {
  const RenderModel m = mesh_model(monkey());
  IbsmOptions o = small(16, 128);
  o.layout = ViewLayout::kCmdm18;
  const MetricResult r = compute_ibsm(m, m, o);
  EXPECT_EQ(r.details.at("views").size(), 18u);
  EXPECT_EQ(r.details.at("render").at("layout"), "cmdm18");
}

TEST(Ibsm, SameValuesOnOneAndTwoThreads) {
  const ColoredMesh m = monkey();
  mesh::SamplingOptions s;
  s.points = 50000;
  const RenderModel mesh = mesh_model(m);
  const RenderModel cloud = cloud_model(mesh::sample_surface(m, s));
  IbsmOptions one = small(5, 200), two = one;
  one.threads = 1;
  two.threads = 2;
  const MetricResult a = compute_ibsm(mesh, cloud, one), b = compute_ibsm(mesh, cloud, two);
  ASSERT_EQ(a.values.size(), b.values.size());
  for (std::size_t i = 0; i < a.values.size(); ++i) {
    EXPECT_EQ(a.values[i].second, b.values[i].second) << a.values[i].first;  // same bits
  }
}

std::string file_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(Ibsm, SavedViewsAreTheScoredImagesAndTheReportRendersThemAgain) {
  const fs::path dir = fs::temp_directory_path() / "qm3d_ibsm_saved_views";
  fs::remove_all(dir);
  const fs::path ref = test::reference_dir() / "cmdm" / "monkey2.obj";
  const fs::path dist = test::reference_dir() / "cmdm" / "monkey_simplified.obj";
  Registry registry;
  mesh::register_metrics(registry);
  register_metrics(registry);
  const Input a = registry.read(ref), b = registry.read(dist);
  RunOptions run;
  run.threads = 2;
  const MetricResult r = run_metric(registry.get("ibsm"), a, b, run,
                                    {{"views", 3}, {"resolution", 128}, {"save_views", dir.string()}});
  for (int i = 0; i < 3; ++i) {
    for (const char* which : {"reference", "distorted"}) {
      const fs::path png = dir / ("view_0" + std::to_string(i) + "_" + which + ".png");
      ASSERT_TRUE(fs::exists(png)) << png;
      EXPECT_EQ(file_bytes(png).substr(1, 3), "PNG");
    }
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 6);
  // The report's pairs at the scored resolution are the saved images, byte for byte.
  const std::vector<ViewPair> pairs = result_view_pairs(r, a, b, 128, 2);
  ASSERT_EQ(pairs.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const std::string saved = file_bytes(dir / ("view_0" + std::to_string(i) + "_reference.png"));
    const std::vector<std::uint8_t> png = png_bytes(pairs[i].reference);
    EXPECT_EQ(std::string(png.begin(), png.end()), saved);
  }
  EXPECT_THROW(result_view_pairs(MetricResult{}, a, b, 64), std::invalid_argument);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace qm3d::render
