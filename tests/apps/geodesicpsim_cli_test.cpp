// `qm3d geodesicpsim` end to end (issue 43): every row of the reference table from the tool's
// JSON, the keypoint map, and bad input refused with one line naming the file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.h"
#include "mesh/geodesicpsim_cases.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;

class GeodesicPsimCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_geodesicpsim_cli_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "io");
    inputs_ = test::geodesicpsim_inputs();
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs in the folder of the gunzipped inputs, where the table's file names are relative.
  test::CliRun qm3d(const std::string& args) { return test::run_qm3d(args, inputs_, dir_ / "io"); }

  fs::path dir_, inputs_;
};

TEST_F(GeodesicPsimCli, EveryReferenceRowFromTheToolsJson) {
  for (const test::CsvRow& row : test::geodesicpsim_reference_rows()) {
    const std::string n = row.at("N_arg") == "default" ? "" : " --keypoints " + row.at("N_arg");
    const auto run =
        qm3d("geodesicpsim " + row.at("ref_obj") + " " + row.at("dis_obj") + n + " --json");
    ASSERT_EQ(run.code, 0) << row.at("case") << ": " << run.err;
    const nlohmann::json j = nlohmann::json::parse(run.out);
    EXPECT_EQ(j["metric"], "geodesicpsim");
    EXPECT_EQ(j["reproduces"], "Qi-Yangsjtu/GeodesicPSIM @ 3e06453");
    const std::pair<std::string, double> values[] = {{"score", j["score"].get<double>()},
                                                     {"pcs", j["features"]["pcs"].get<double>()},
                                                     {"dmc", j["features"]["dmc"].get<double>()},
                                                     {"pca", j["features"]["pca"].get<double>()},
                                                     {"pcv", j["features"]["pcv"].get<double>()}};
    for (const auto& [col, ours] : values) {
      const double want = std::stod(row.at(col));
      EXPECT_LE(std::fabs(ours - want), 1e-9 * std::fabs(want))
          << row.at("case") << " " << col << ": " << ours << " vs " << want;
    }
    EXPECT_EQ(j["keypoints"].get<int>(), std::stoi(row.at("N_used"))) << row.at("case");
    EXPECT_EQ(j["flag1"].get<int>(), std::stoi(row.at("flag1"))) << row.at("case");
    EXPECT_EQ(j["flag2"].get<int>(), std::stoi(row.at("flag2"))) << row.at("case");
    EXPECT_EQ(j["flag3"].get<int>(), std::stoi(row.at("flag3"))) << row.at("case");
    EXPECT_EQ(j["effective_patches"].get<int>(), std::stoi(row.at("effective_patches")));
    EXPECT_EQ(j["subdivided"], row.at("subdivided")) << row.at("case");
  }
}

TEST_F(GeodesicPsimCli, MapsTheKeypointsOfThePooledPatches) {
  const std::string map = (dir_ / "keypoints.ply").string();
  const auto run = qm3d("geodesicpsim tblob4_ref.obj tblob4_dec50.obj --keypoints 100 --map '" +
                        map + "' --json");
  ASSERT_EQ(run.code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  const std::string ply = test::slurp(map);
  const std::string header = "element vertex " + std::to_string(j["effective_patches"].get<int>());
  EXPECT_NE(ply.find(header), std::string::npos) << ply.substr(0, 400);
  EXPECT_NE(ply.find("scalar_pcs"), std::string::npos);
  EXPECT_EQ(ply.find("element face"), std::string::npos);
}

TEST_F(GeodesicPsimCli, TheReportColoursTheKeypoints) {
  const auto run = qm3d("geodesicpsim tblob4_ref.obj tblob4_dec50.obj --keypoints 100 --report '" +
                        (dir_ / "r.html").string() + "' -q");
  ASSERT_EQ(run.code, 0) << run.err;
  const std::string html = test::slurp(dir_ / "r.html");
  EXPECT_NE(html.find("geodesicpsim points on the reference"), std::string::npos);
}

TEST_F(GeodesicPsimCli, BadInputGetsOneLineNamingTheFile) {
  std::ofstream(dir_ / "plain.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const auto run = qm3d("geodesicpsim tblob4_ref.obj '" + (dir_ / "plain.obj").string() + "'");
  EXPECT_EQ(run.code, 2);
  EXPECT_NE(run.err.find("plain.obj"), std::string::npos) << run.err;
  EXPECT_LE(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
}

}  // namespace
}  // namespace qm3d
