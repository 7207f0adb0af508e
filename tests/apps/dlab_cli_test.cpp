// `qm3d dlab` end to end (issue 26 item 4): the JSON and text output on the bundled meshes and
// clouds, each direction, the map on the iterated mesh with its faces, compare and batch listing
// it, and an input without colours refused with one line naming the file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.h"
#include "qm3d/common/ply.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;

class DlabCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_dlab_cli_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "io");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs in the repository's data/, where the bundled stimuli are.
  test::CliRun qm3d(const std::string& args) {
    return test::run_qm3d(args, test::source_dir() / "data", dir_ / "io",
                          "QM3D_DATA_DIR='" + test::tables_dir().string() + "'");
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

constexpr const char* kMeshes = "meshes/blob3_ref.off meshes/blob3_colnoise.off";
constexpr const char* kClouds = "clouds/sphere_2k_ref.ply clouds/sphere_2k_cnoise10.ply";

nlohmann::json json_of(const test::CliRun& run) {
  EXPECT_EQ(run.code, 0) << run.err;
  return nlohmann::json::parse(run.out);
}

TEST_F(DlabCli, JsonHasBothDirectionsTheirMeanAndTheCorrespondence) {
  for (const char* pair : {kMeshes, kClouds}) {
    SCOPED_TRACE(pair);
    const nlohmann::json j = json_of(qm3d(std::string("dlab ") + pair + " --json"));
    EXPECT_EQ(j["metric"], "dlab");
    const double a = j["directions"]["ref_to_dist"]["score"].get<double>();
    const double b = j["directions"]["dist_to_ref"]["score"].get<double>();
    EXPECT_GT(a, 1.0);
    EXPECT_EQ(j["score"].get<double>(), (a + b) / 2);
    EXPECT_EQ(j["features"]["delta_e_mean"], j["score"]);
    EXPECT_GE(j["features"]["delta_e_max"].get<double>(), j["score"].get<double>());
    EXPECT_EQ(j["options"]["direction"], "symmetric");
    const bool meshes = std::string(pair) == kMeshes;
    EXPECT_EQ(j["options"]["correspondence"], meshes ? "surface" : "nearest point");
    EXPECT_EQ(j["correspondence"].get<std::string>().rfind(meshes ? "closest point" : "nearest", 0),
              0u);
    EXPECT_TRUE(j["warnings"].empty()) << j["warnings"];
  }
  // Identical inputs: exactly 0.
  const nlohmann::json same =
      json_of(qm3d("dlab meshes/blob3_ref.off meshes/blob3_ref.off --json"));
  EXPECT_EQ(same["score"].get<double>(), 0.0);
}

TEST_F(DlabCli, TextIsOneLineWithTheDirectionsAndTheCorrespondence) {
  const auto run = qm3d(std::string("dlab ") + kMeshes);
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_EQ(run.out.rfind("DLAB = 4.13422  (dist→ref 4.13422, ref→dist 4.13422)", 0), 0u)
      << run.out;
  EXPECT_NE(run.out.find("closest point on the other surface (CMDM's projection)"),
            std::string::npos)
      << run.out;
  EXPECT_EQ(run.out.find('\n'), run.out.size() - 1) << run.out;
  const auto self = qm3d("dlab clouds/sphere_2k_ref.ply clouds/sphere_2k_ref.ply");
  EXPECT_EQ(self.out.rfind("DLAB = 0  ", 0), 0u) << self.out;
}

TEST_F(DlabCli, OneDirectionAndItsMapOnTheIteratedMesh) {
  const nlohmann::json j = json_of(qm3d(std::string("dlab ") + kMeshes +
                                        " --direction ref-to-dist --json --map " + path("m.ply")));
  EXPECT_FALSE(j["directions"].contains("dist_to_ref"));
  EXPECT_EQ(j["score"], j["directions"]["ref_to_dist"]["score"]);
  const ply::Content map = ply::parse(test::slurp(path("m.ply")), "m.ply");
  EXPECT_EQ(map.positions.size(), 642u);
  EXPECT_EQ(map.face_offsets.size(), 1281u);  // the mesh's faces are kept
}

TEST_F(DlabCli, CompareAndBatchListIt) {
  const nlohmann::json clouds = json_of(qm3d(std::string("compare ") + kClouds + " --json -q"));
  ASSERT_TRUE(clouds["metrics"].contains("dlab"));
  const nlohmann::json alone = json_of(qm3d(std::string("dlab ") + kClouds + " --json"));
  EXPECT_EQ(clouds["metrics"]["dlab"]["score"], alone["score"]);
  const nlohmann::json mixed =
      json_of(qm3d("compare meshes/blob3_ref.off clouds/sphere_2k_ref.ply --json -q"));
  ASSERT_TRUE(mixed["metrics"].contains("dlab"));
  EXPECT_EQ(mixed["metrics"]["dlab"]["options"]["correspondence"], "nearest point");
  const std::string data = (test::source_dir() / "data").string();
  std::ofstream(path("list.csv")) << "reference,distorted,metric\n"
                                  << data << "/meshes/blob3_ref.off," << data
                                  << "/meshes/blob3_colnoise.off,dlab\n";
  const auto batch = qm3d("batch " + path("list.csv") + " -o " + path("out.csv") + " -q");
  ASSERT_EQ(batch.code, 0) << batch.err << test::slurp(path("out.csv"));
  const std::string csv = test::slurp(path("out.csv"));
  EXPECT_NE(csv.find(",dlab,4.13421776"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",delta_e_mean,delta_e_max"), std::string::npos) << csv;
}

TEST_F(DlabCli, AnInputWithoutColoursIsOneLineNamingTheFile) {
  ply::WriteData w;
  w.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  ply::write(path("plain.ply"), w);
  std::ofstream(path("plain.off")) << "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  for (const std::string& args : {"clouds/sphere_2k_ref.ply " + path("plain.ply"),
                                  "meshes/blob3_ref.off " + path("plain.off")}) {
    SCOPED_TRACE(args);
    const auto run = qm3d("dlab " + args);
    EXPECT_EQ(run.code, 2);
    EXPECT_NE(run.err.find("plain."), std::string::npos) << run.err;
    EXPECT_NE(run.err.find(": no vertex colours (dlab"), std::string::npos) << run.err;
    EXPECT_EQ(run.err.find('\n'), run.err.size() - 1) << run.err;
  }
}

}  // namespace
}  // namespace qm3d
