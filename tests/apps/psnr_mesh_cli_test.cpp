// `qm3d psnr` on two meshes and `qm3d sample --mode grid` end to end (issue 28): every value of
// mmetric's mesh table from the tool's JSON (but mm_pcc_monkey_g1024, 1.9M samples per mesh,
// which bench/run_benchmarks.sh psnr_mesh checks), the grid samples written as mmetric writes
// them, and bad input refused with one line naming the file.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "cli_runner.h"
#include "mpeg_reference.h"
#include "qm3d/common/ply.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;

class PsnrMeshCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_psnr_mesh_cli_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "io");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs in shared/data, where the table's paths are relative.
  test::CliRun qm3d(const std::string& args) {
    return test::run_qm3d(args, test::shared_data(), dir_ / "io",
                          "QM3D_DATA_DIR='" + test::tables_dir().string() + "'");
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

TEST_F(PsnrMeshCli, EveryMmetricMeshCaseFromTheToolsJson) {
  int checked = 0;
  for (const test::PcErrorCase& c : test::mmetric_mesh_cases()) {
    if (c.name == "mm_pcc_monkey_g1024") continue;
    SCOPED_TRACE(c.name);
    const auto run = qm3d("psnr " + c.column.at("mesh_a") + " " + c.column.at("mesh_b") +
                          test::qm3d_mesh_flags(c) + " --json -q");
    ASSERT_EQ(run.code, 0) << run.err;
    const nlohmann::json j = nlohmann::json::parse(run.out);
    test::expect_pc_error_json(c, j);
    test::expect_mmetric_statistics(c, j["features"]);
    EXPECT_EQ(j["sampling"]["grid_size"].get<int>(), std::stoi(c.column.at("gridSize")));
    EXPECT_EQ(j["conventions"]["tie_threshold"].get<double>(), 1e-20);
    EXPECT_EQ(j["reproduces"], "MPEG mmetric 1.1.7 (MPEGGroup/mpeg-pcc-mmetric @ 5faa660)");
    ++checked;
  }
  EXPECT_EQ(checked, 15);
}

TEST_F(PsnrMeshCli, SampleGridWritesMmetricsCloud) {
  const auto run = qm3d(
      "sample reference/cmdm/blob4_bothnoise.ply --mode grid --grid-size 100 --normals --box "
      "-0.997778773 -1.05314529 -1.04921687 1.05481851 1.04963803 1.05762815 -o " +
      path("g100.ply"));
  ASSERT_EQ(run.code, 0) << run.err;
  const ply::Content ours = ply::read(path("g100.ply"), ply::AsciiFloat::kAsDeclared);
  const ply::Content theirs =
      ply::read(test::reference_dir() / "mpeg" / "sampled" / "blob4_bothnoise_g100.ply",
                ply::AsciiFloat::kAsDeclared);
  ASSERT_EQ(ours.positions.size(), 24409u);
  EXPECT_TRUE(ours.positions == theirs.positions);
  EXPECT_TRUE(ours.normals == theirs.normals);
  ASSERT_EQ(ours.colors.size(), theirs.colors.size());
  std::size_t colours_differ = 0;
  for (std::size_t i = 0; i < ours.colors.size(); ++i) {
    colours_differ += ours.colors[i].r != theirs.colors[i].r ||
                      ours.colors[i].g != theirs.colors[i].g ||
                      ours.colors[i].b != theirs.colors[i].b;
  }
  EXPECT_EQ(colours_differ, 0u);
  // The sampled clouds compared as clouds give pc_error's values of the table's case.
  const auto cloud = qm3d("psnr reference/mpeg/sampled/blob4_ref_g100.ply " + path("g100.ply") +
                          " --peak 3.61575 --json -q");
  ASSERT_EQ(cloud.code, 0) << cloud.err;
  for (const test::PcErrorCase& c : test::pc_error_cases()) {
    if (c.name == "mesh_blob4_bothnoise_g100") {
      test::expect_pc_error_json(c, nlohmann::json::parse(cloud.out));
    }
  }
}

TEST_F(PsnrMeshCli, AMeshWithoutColoursGivesGeometryWithAWarning) {
  std::ofstream(path("plain.off")) << "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0.2\n3 0 1 2\n3 0 2 3\n";
  const auto run = qm3d("psnr " + path("plain.off") + " " + path("plain.off") +
                        " --grid-size 64 --json");
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_NE(run.err.find("no vertex colours: geometry values only"), std::string::npos)
      << run.err;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  EXPECT_TRUE(j["features"]["d1_psnr"].is_null());  // identical: infinite
  EXPECT_FALSE(j["features"].contains("c0_psnr"));
}

TEST_F(PsnrMeshCli, ZeroAreaFacesAreReportedNotFatal) {
  const auto run = qm3d("psnr reference/mpeg/meshes/blob5_ref.ply "
                        "reference/mpeg/meshes/blob5_pquant6.ply --grid-size 64");
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_NE(run.err.find("faces of zero area were not sampled"), std::string::npos) << run.err;
}

TEST_F(PsnrMeshCli, BadInputIsOneLineNamingTheFile) {
  const auto mixed = qm3d("psnr reference/cmdm/blob4_ref.ply "
                          "reference/mpeg/sampled/blob4_ref_g100.ply");
  EXPECT_EQ(mixed.code, 2);
  EXPECT_NE(mixed.err.find("psnr"), std::string::npos) << mixed.err;
  EXPECT_EQ(std::count(mixed.err.begin(), mixed.err.end(), '\n'), 1) << mixed.err;
  const auto cloud = qm3d("sample reference/mpeg/sampled/blob4_ref_g100.ply --mode grid -o " +
                          path("x.ply"));
  EXPECT_EQ(cloud.code, 2);
  EXPECT_NE(cloud.err.find("blob4_ref_g100.ply: a point cloud"), std::string::npos) << cloud.err;
  EXPECT_FALSE(fs::exists(path("x.ply")));
  const auto flat = qm3d("sample reference/cmdm/blob4_ref.ply --mode grid --box 0 0 0 1 0 0 -o " +
                         path("y.ply"));
  EXPECT_EQ(flat.code, 2);
  EXPECT_NE(flat.err.find("blob4_ref.ply"), std::string::npos) << flat.err;
  EXPECT_NE(flat.err.find("flat"), std::string::npos) << flat.err;
  const auto points = qm3d("sample reference/cmdm/blob4_ref.ply --mode grid --points 10 -o " +
                           path("z.ply"));
  EXPECT_NE(points.code, 0);
}

}  // namespace
}  // namespace qm3d
