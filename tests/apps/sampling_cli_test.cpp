// End-to-end tests of `qm3d sample`, `qm3d texture-to-vertex`, and sampled PCQM in `compare` and
// `batch`, on the bundled stimuli (data/meshes/blob3_*).
#include <gtest/gtest.h>
#include <stb/stb_image_write.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "qm3d/mesh/mesh_io.h"
#include "qm3d/pointcloud/cloud_io.h"
#include "cli_runner.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;

using CliResult = test::CliRun;
using test::slurp;

std::string bundled(const std::string& name) {
  return (test::source_dir() / "data" / "meshes" / name).string();
}

class SamplingCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_sampling_cli_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  CliResult qm3d(const std::string& args) {
    return test::run_qm3d(args, dir_, dir_);
  }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

TEST_F(SamplingCli, SampleWritesTheRequestedCloudDeterministically) {
  const std::string ref = bundled("blob3_ref.off");
  ASSERT_EQ(qm3d("sample " + ref + " -o " + path("a.ply") + " --points 3000 --seed 5").code, 0);
  ASSERT_EQ(
      qm3d("--threads 1 sample " + ref + " -o " + path("b.ply") + " --points 3000 --seed 5").code,
      0);
  ASSERT_EQ(qm3d("sample " + ref + " -o " + path("c.ply") + " --points 3000 --seed 6").code, 0);
  EXPECT_EQ(pointcloud::read_cloud(path("a.ply")).size(), 3000u);
  EXPECT_EQ(slurp(path("a.ply")), slurp(path("b.ply")));
  EXPECT_NE(slurp(path("a.ply")), slurp(path("c.ply")));
  ASSERT_EQ(qm3d("sample " + ref + " -o " + path("v.ply") + " --vertices").code, 0);
  EXPECT_EQ(pointcloud::read_cloud(path("v.ply")).size(), 642u);
  ASSERT_EQ(qm3d("sample " + ref + " -o " + path("d.ply") + " --density 100").code, 0);
  EXPECT_GT(pointcloud::read_cloud(path("d.ply")).size(), 100u);
}

TEST_F(SamplingCli, SampleUsageErrors) {
  const std::string ref = bundled("blob3_ref.off");
  EXPECT_EQ(qm3d("sample " + ref + " -o " + path("a.ply")).code, 1);  // no count
  EXPECT_EQ(qm3d("sample " + ref + " -o " + path("a.ply") + " --points 5 --density 2").code, 1);
  EXPECT_EQ(qm3d("sample " + ref + " -o " + path("a.ply") + " --points 5 --vertices").code, 1);
  const CliResult missing = qm3d("sample /nonexistent.off -o " + path("a.ply") + " --points 5");
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.err.find("/nonexistent.off"), std::string::npos) << missing.err;
}

TEST_F(SamplingCli, CompareJsonHasEveryMetricFiniteOnTheBundledData) {
  const CliResult r = qm3d("compare " + bundled("blob3_ref.off") + " " +
                           bundled("blob3_bothnoise.off") + " --json --points 5000 --seed 2");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* metric : {"cmdm", "msdm2", "pcqm", "pcqm_sampled", "dlab"}) {
    ASSERT_TRUE(j["metrics"].contains(metric)) << metric;
    const double score = j["metrics"][metric]["score"].get<double>();
    EXPECT_TRUE(std::isfinite(score)) << metric;
    EXPECT_GT(score, 0) << metric;
  }
  EXPECT_EQ(j["metrics"]["pcqm_sampled"]["options"]["sampling"]["points"], 5000);
  EXPECT_EQ(j["metrics"]["pcqm_sampled"]["options"]["sampling"]["seed"], 2);
  // Same settings on both sides: a mesh against itself scores 0.
  const CliResult same = qm3d("compare " + bundled("blob3_ref.off") + " " +
                              bundled("blob3_ref.off") + " --json --points 2000");
  ASSERT_EQ(same.code, 0) << same.err;
  EXPECT_NEAR(nlohmann::json::parse(same.out)["metrics"]["pcqm_sampled"]["score"].get<double>(),
              0.0, 1e-12);
}

TEST_F(SamplingCli, BatchCompareWritesOneRowPerMetricAndResumes) {
  const fs::path list = dir_ / "list.csv", results = dir_ / "results.csv";
  std::ofstream(list) << "reference,distorted,metric\n"
                      << bundled("blob3_ref.off") << "," << bundled("blob3_colnoise.off")
                      << ",compare\n";
  const std::string cmd =
      "batch " + list.string() + " -o " + results.string() + " --points 2000 --quiet";
  ASSERT_EQ(qm3d(cmd).code, 0);
  const std::string csv = slurp(results);
  for (const char* m : {",cmdm,", ",msdm2,", ",pcqm,", ",pcqm_sampled,", ",dlab,"}) {
    EXPECT_NE(csv.find(m), std::string::npos) << m << "\n" << csv;
  }
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 6);  // header + 5 rows
  ASSERT_EQ(qm3d(cmd + " --resume").code, 0);
  EXPECT_EQ(slurp(results), csv);  // nothing left to do
}

TEST_F(SamplingCli, TextureToVertexWritesTheTextureColours) {
  const unsigned char texels[] = {255, 0, 0, 0, 0, 255};  // 2 x 1: red, blue
  ASSERT_NE(stbi_write_png(path("t.png").c_str(), 2, 1, 3, texels, 6), 0);
  std::ofstream(dir_ / "t.mtl") << "newmtl m\nmap_Kd t.png\n";
  std::ofstream(dir_ / "t.obj") << "mtllib t.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                                   "vt 0.25 0.5\nvt 0.75 0.5\nf 1/1 2/2 3/1\n";
  const CliResult r = qm3d("texture-to-vertex " + path("t.obj") + " -o " + path("t.ply"));
  ASSERT_EQ(r.code, 0) << r.err;
  const ColoredMesh m = mesh::read_mesh(path("t.ply")).mesh;
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.colors[0].r, 1.0);
  EXPECT_EQ(m.colors[1].b, 1.0);
  // Every metric reads the textured OBJ directly.
  const CliResult cmdm = qm3d("cmdm " + path("t.obj") + " " + path("t.ply"));
  EXPECT_EQ(cmdm.code, 0) << cmdm.err;
  std::ofstream(dir_ / "t.mtl") << "newmtl m\nmap_Kd gone.png\n";
  const CliResult missing = qm3d("texture-to-vertex " + path("t.obj") + " -o " + path("u.ply"));
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.err.find("gone.png"), std::string::npos) << missing.err;
}

}  // namespace
}  // namespace qm3d
