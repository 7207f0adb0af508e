// D_LAB (pointcloud_metric/src/dlab.cpp, its mesh side mesh_metric/src/surface_colours.cpp),
// through the registry as the tool runs it: identity gives exactly 0, swapping the inputs swaps
// the directions, hand-derived clouds and meshes, the same bits for any thread count, and
// inputs without colours refused with one line naming the file.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "qm3d/common/color.h"
#include "qm3d/common/error.h"
#include "qm3d/common/metric.h"
#include "qm3d/mesh/metrics.h"
#include "qm3d/pointcloud/metrics.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;

const Registry& registry() {
  static const Registry r = [] {
    Registry out;
    mesh::register_metrics(out);
    pointcloud::register_metrics(out);
    return out;
  }();
  return r;
}

std::string bundled(const std::string& name) {
  const bool cloud = name.rfind("sphere", 0) == 0;
  return (test::source_dir() / "data" / (cloud ? "clouds" : "meshes") / name).string();
}

MetricResult dlab(const Input& ref, const Input& dist, int threads = 0,
                  std::optional<Direction> direction = std::nullopt) {
  RunOptions run;
  run.threads = threads;
  run.direction = direction;
  return run_metric(registry().get("dlab"), ref, dist, run);
}

MetricResult dlab(const std::string& ref, const std::string& dist, int threads = 0) {
  return dlab(registry().read(ref), registry().read(dist), threads);
}

const Lab2000hlTable& table() { return *Lab2000hlTable::shared(resolve_data_dir()); }

double distance(const Lab& x, const Lab& y) {
  return std::sqrt((x.L - y.L) * (x.L - y.L) + (x.a - y.a) * (x.a - y.a) +
                   (x.b - y.b) * (x.b - y.b));
}

TEST(Dlab, IsRegisteredAsADistortionOfEveryPair) {
  const MetricSpec& s = registry().get("dlab");
  EXPECT_FALSE(s.higher_is_better);
  EXPECT_EQ(s.applies_to, AppliesTo::kBoth);
  EXPECT_EQ(s.default_direction, Direction::kSymmetric);
  EXPECT_TRUE(s.options.empty());
  // Two meshes are read as meshes (CMDM's projection), a mesh and a cloud as clouds.
  const Input mesh = registry().read(bundled("blob3_ref.off"));
  const Input cloud = registry().read(bundled("sphere_2k_ref.ply"));
  EXPECT_EQ(s.reads_for(mesh, mesh), Input::Kind::kMesh);
  EXPECT_EQ(s.reads_for(mesh, cloud), Input::Kind::kCloud);
  EXPECT_EQ(s.reads_for(cloud, cloud), Input::Kind::kCloud);
  // PCQM stays the first metric for two clouds (auto), CMDM for two meshes.
  EXPECT_EQ(registry().auto_metric(cloud, cloud).name, "pcqm");
  EXPECT_EQ(registry().auto_metric(mesh, mesh).name, "cmdm");
}

TEST(Dlab, IdenticalInputsGiveExactlyZero) {
  for (const char* name : {"sphere_2k_ref.ply", "blob3_ref.off", "blob3_colnoise.off"}) {
    SCOPED_TRACE(name);
    const MetricResult r = dlab(bundled(name), bundled(name));
    EXPECT_EQ(r.score, 0.0);
    ASSERT_TRUE(r.ref_to_dist && r.dist_to_ref);
    for (const auto* d : {&*r.ref_to_dist, &*r.dist_to_ref}) {
      EXPECT_EQ(d->score, 0.0);
      EXPECT_EQ(*find_value(d->values, "delta_e_max"), 0.0);
      for (double v : d->per_element) ASSERT_EQ(v, 0.0);
    }
  }
}

TEST(Dlab, SwappingTheInputsSwapsTheDirections) {
  const std::pair<const char*, const char*> pairs[] = {
      {"sphere_2k_ref.ply", "sphere_2k_gnoise0.005.ply"},
      {"sphere_2k_ref.ply", "sphere_2k_down0.5.ply"},
      {"blob3_ref.off", "blob3_bothnoise.off"},
      {"blob3_ref.off", "sphere_2k_cnoise10.ply"}};  // a mesh and a cloud: both as clouds
  for (const auto& [a, b] : pairs) {
    SCOPED_TRACE(std::string(a) + " " + b);
    const MetricResult ab = dlab(bundled(a), bundled(b));
    const MetricResult ba = dlab(bundled(b), bundled(a));
    EXPECT_GT(ab.score, 0.0);
    EXPECT_EQ(ab.score, ba.score);
    EXPECT_EQ(ab.ref_to_dist->score, ba.dist_to_ref->score);
    EXPECT_EQ(ab.dist_to_ref->score, ba.ref_to_dist->score);
    EXPECT_EQ(ab.ref_to_dist->per_element, ba.dist_to_ref->per_element);
    EXPECT_EQ(ab.score, (ab.ref_to_dist->score + ab.dist_to_ref->score) / 2);
  }
}

TEST(Dlab, ThreeColouredPointsByHand) {
  const Rgb red{1, 0, 0}, green{0, 1, 0}, blue{0, 0, 1};
  const Rgb grey{0.5, 0.5, 0.5}, white{1, 1, 1}, dark{0.2, 0.1, 0.4};
  ColoredCloud ref{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {red, green, blue}};
  ColoredCloud dist{{{0.1, 0, 0}, {0, 0.2, 0}, {0, 0.9, 0}}, {grey, white, dark}};
  const auto lab = [](const Rgb& c) { return table().from_srgb(c); };
  // ref -> dist: ref0 and ref1 have dist0 nearest, ref2 dist2.
  const double ref_to_dist[] = {distance(lab(red), lab(grey)), distance(lab(green), lab(grey)),
                                distance(lab(blue), lab(dark))};
  // dist -> ref: dist0 and dist1 have ref0 nearest, dist2 ref2.
  const double dist_to_ref[] = {distance(lab(grey), lab(red)), distance(lab(white), lab(red)),
                                distance(lab(dark), lab(blue))};
  const MetricResult r = dlab(Input::from_cloud(ref, "ref"), Input::from_cloud(dist, "dist"), 1);
  ASSERT_EQ(r.ref_to_dist->per_element.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(r.ref_to_dist->per_element[i], ref_to_dist[i]) << i;
    EXPECT_EQ(r.dist_to_ref->per_element[i], dist_to_ref[i]) << i;
  }
  const double a = (ref_to_dist[0] + ref_to_dist[1] + ref_to_dist[2]) / 3;
  const double b = (dist_to_ref[0] + dist_to_ref[1] + dist_to_ref[2]) / 3;
  EXPECT_EQ(r.ref_to_dist->score, a);
  EXPECT_EQ(r.dist_to_ref->score, b);
  EXPECT_EQ(r.score, (a + b) / 2);
  EXPECT_EQ(*find_value(r.values, "delta_e_mean"), r.score);
  EXPECT_EQ(*find_value(r.values, "delta_e_max"),
            std::max({ref_to_dist[0], ref_to_dist[1], ref_to_dist[2], dist_to_ref[0],
                      dist_to_ref[1], dist_to_ref[2]}));
  EXPECT_GT(r.score, 0.0);
  // One direction alone.
  const MetricResult one = dlab(Input::from_cloud(ref, "ref"), Input::from_cloud(dist, "dist"), 1,
                                Direction::kRefToDist);
  EXPECT_FALSE(one.dist_to_ref);
  EXPECT_EQ(one.score, a);
}

// A triangle inside a larger one in the same plane: each small-triangle vertex projects onto
// itself, where the barycentric weights are known; each large-triangle corner's closest point on
// the small triangle is a corner.
TEST(Dlab, TwoTrianglesByHand) {
  const Rgb c0{0.9, 0.2, 0.1}, c1{0.1, 0.8, 0.3}, c2{0.2, 0.3, 0.9};
  const Rgb s0{0.5, 0.5, 0.5}, s1{0.7, 0.6, 0.1}, s2{0.05, 0.1, 0.2};
  const ColoredMesh small{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {s0, s1, s2}, {{0, 1, 2}}};
  const ColoredMesh large{{{-1, -1, 0}, {3, -1, 0}, {-1, 3, 0}}, {c0, c1, c2}, {{0, 1, 2}}};
  const auto lab = [](const Rgb& c) { return table().from_srgb(c); };
  const auto mix = [&](double w0, double w1, double w2) {
    const Lab x = lab(c0), y = lab(c1), z = lab(c2);
    return Lab{w0 * x.L + w1 * y.L + w2 * z.L, w0 * x.a + w1 * y.a + w2 * z.a,
               w0 * x.b + w1 * y.b + w2 * z.b};
  };
  // Barycentric weights of (0,0), (1,0), (0,1) in the large triangle (areas over 8).
  const Lab on_large[] = {mix(0.5, 0.25, 0.25), mix(0.25, 0.5, 0.25), mix(0.25, 0.25, 0.5)};
  const Rgb small_colours[] = {s0, s1, s2}, large_colours[] = {c0, c1, c2};
  const MetricResult r = dlab(Input::from_mesh(small, "small"), Input::from_mesh(large, "large"));
  ASSERT_EQ(r.details.at("correspondence").get<std::string>().find("closest point"), 0u);
  double sum_small = 0, sum_large = 0;
  for (int i = 0; i < 3; ++i) {
    const double expected_small = distance(lab(small_colours[i]), on_large[i]);
    EXPECT_NEAR(r.ref_to_dist->per_element[i], expected_small, 1e-12 * expected_small) << i;
    sum_small += expected_small;
    // (-1,-1) -> (0,0), (3,-1) -> (1,0), (-1,3) -> (0,1): the corners' own colours.
    const double expected_large = distance(lab(large_colours[i]), lab(small_colours[i]));
    EXPECT_EQ(r.dist_to_ref->per_element[i], expected_large) << i;
    sum_large += expected_large;
  }
  EXPECT_NEAR(r.score, (sum_small / 3 + sum_large / 3) / 2, 1e-12 * r.score);
}

TEST(Dlab, SameBitsForAnyThreadCount) {
  for (const auto& [a, b] :
       {std::pair<const char*, const char*>{"sphere_2k_ref.ply", "sphere_2k_gnoise0.005.ply"},
        {"blob3_ref.off", "blob3_bothnoise.off"}}) {
    SCOPED_TRACE(a);
    const MetricResult one = dlab(bundled(a), bundled(b), 1);
    for (int threads : {2, 3}) {
      const MetricResult many = dlab(bundled(a), bundled(b), threads);
      EXPECT_EQ(one.score, many.score);
      EXPECT_EQ(one.ref_to_dist->per_element, many.ref_to_dist->per_element);
      EXPECT_EQ(one.dist_to_ref->per_element, many.dist_to_ref->per_element);
    }
  }
}

// Stronger colour noise, larger D_LAB; the same mesh as OFF, PLY or OBJ, the same score (to the
// OBJ's printed colour digits).
TEST(Dlab, GrowsWithColourNoiseAndIgnoresTheFileFormat) {
  const fs::path pcqm = test::reference_dir() / "pcqm", cmdm = test::reference_dir() / "cmdm";
  const std::string ref = (pcqm / "sphere_50k_ref.ply").string();
  const double weak = dlab(ref, (pcqm / "sphere_50k_cnoise10.ply").string()).score;
  const double strong = dlab(ref, (pcqm / "sphere_50k_cnoise30.ply").string()).score;
  EXPECT_GT(weak, 1.0);
  EXPECT_GT(strong, 2 * weak);
  const double off =
      dlab((cmdm / "blob4_ref.off").string(), (cmdm / "blob4_colnoise.off").string()).score;
  const auto score = [&](const char* ext) {
    return dlab((cmdm / ("blob4_ref" + std::string(ext))).string(),
                (cmdm / ("blob4_colnoise" + std::string(ext))).string())
        .score;
  };
  EXPECT_EQ(score(".ply"), off);
  EXPECT_NEAR(score(".obj"), off, 1e-8 * off);  // its colours are written with 6 decimals
}

class DlabFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / "qm3d_dlab_test";
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  fs::path dir_;
};

void expect_one_line_naming(const std::function<void()>& run, const std::string& file) {
  try {
    run();
    ADD_FAILURE() << "no error for " << file;
  } catch (const FormatError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(file), std::string::npos) << m;
    EXPECT_NE(m.find("colour"), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
}

TEST_F(DlabFiles, InputsWithoutColoursAreRefusedNamingTheFile) {
  const std::string cloud = write("grey.ply",
                                  "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                  "property float y\nproperty float z\nend_header\n"
                                  "0 0 0\n1 0 0\n0 1 0\n");
  const std::string mesh = write("grey.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  const std::string ref_cloud = bundled("sphere_2k_ref.ply");
  const std::string ref_mesh = bundled("blob3_ref.off");
  expect_one_line_naming([&] { dlab(ref_cloud, cloud); }, cloud);
  expect_one_line_naming([&] { dlab(cloud, ref_cloud); }, cloud);
  expect_one_line_naming([&] { dlab(ref_mesh, mesh); }, mesh);
  expect_one_line_naming([&] { dlab(mesh, ref_mesh); }, mesh);
}

}  // namespace
}  // namespace qm3d
