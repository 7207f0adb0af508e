// `qm3d psnr` end to end (issue 25): every value of the pc_error reference table from the tool's
// JSON, the peak echoed, infinite values in text/CSV/JSON, the named-value CSV columns (single
// runs, compare, batch), and bad input refused with one line naming the file.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "cli_runner.h"
#include "mpeg_reference.h"
#include "qm3d/common/ply.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;

class PsnrCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_psnr_cli_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "io");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs in shared/data, where the table's paths are relative.
  test::CliRun qm3d(const std::string& args, const fs::path& cwd = test::shared_data()) {
    return test::run_qm3d(args, cwd, dir_ / "io",
                          "QM3D_DATA_DIR='" + test::tables_dir().string() + "'");
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};


TEST_F(PsnrCli, EveryPcErrorReferenceCaseFromTheToolsJson) {
  const auto cases = test::pc_error_cases();
  ASSERT_EQ(cases.size(), 28u);
  for (const test::PcErrorCase& c : cases) {
    SCOPED_TRACE(c.name);
    const auto run = qm3d("psnr " + c.column.at("a") + " " + c.column.at("b") +
                          test::qm3d_flags(c) + " --json -q");
    ASSERT_EQ(run.code, 0) << run.err;
    const nlohmann::json j = nlohmann::json::parse(run.out);
    test::expect_pc_error_json(c, j);
    const double peak = std::stod(c.column.at("peak"));
    EXPECT_NEAR(j["peak"].get<double>(), peak, 1e-8 * peak);
    EXPECT_EQ(j["metric"], "psnr");
  }
}

TEST_F(PsnrCli, TextEchoesThePeakAndWritesInf) {
  const auto self = qm3d("psnr reference/mpeg/vox1_ref_n.ply reference/mpeg/vox1_ref_n.ply");
  ASSERT_EQ(self.code, 0) << self.err;
  EXPECT_EQ(self.out.rfind("PSNR = inf", 0), 0u) << self.out;
  EXPECT_NE(self.out.find("peak 1 (largest nearest-neighbour distance in the reference)"),
            std::string::npos)
      << self.out;
  const auto given = qm3d("psnr reference/mpeg/vox1_ref_n.ply reference/voxel/vox1_requant8.ply "
                          "--peak 1023");
  ASSERT_EQ(given.code, 0) << given.err;
  EXPECT_NE(given.out.find("PSNR = 58.1418"), std::string::npos) << given.out;
  EXPECT_NE(given.out.find("peak 1023 (given)"), std::string::npos) << given.out;
}

// --help says which scores are distortions and which qualities (from the registry).
TEST_F(PsnrCli, HelpSaysWhichScoresAreQualities) {
  auto help = qm3d("--help");
  ASSERT_EQ(help.code, 0) << help.err;
  // One line: the help is wrapped to the terminal's width.
  help.out = std::regex_replace(help.out, std::regex("\\s+"), " ");
  EXPECT_NE(help.out.find("Distortions (0 = identical, larger is worse): CMDM, MSDM2, PCQM"),
            std::string::npos)
      << help.out;
  EXPECT_NE(help.out.find("qualities (higher is better; in dB inf = identical, similarities 1 = "
                          "identical): GeodesicPSIM, PSNR, GraphSIM, MS-GraphSIM, "
                          "PointSSIM, IBSM."),
            std::string::npos)
      << help.out;
  EXPECT_EQ(help.out.find("Scores are distortions"), std::string::npos) << help.out;
}

// --version and every JSON result name the commit and the reference tool a metric reproduces.
TEST_F(PsnrCli, VersionNamesTheCommitAndTheReferenceTools) {
  const auto version = qm3d("--version");
  ASSERT_EQ(version.code, 0) << version.err;
  EXPECT_TRUE(std::regex_search(version.out,
                                std::regex("^qm3d [0-9.]+ \\(commit ([0-9a-f]{12}(-dirty)?|unknown)\\)")))
      << version.out;
  EXPECT_NE(version.out.find("psnr: reproduces MPEG pc_error 0.14.2"), std::string::npos)
      << version.out;
  EXPECT_NE(version.out.find("cmdm: reproduces MEPP-team/MEPP2 @ d977d05"), std::string::npos)
      << version.out;
  const auto run = qm3d("psnr reference/mpeg/vox1_ref_n.ply reference/mpeg/vox1_ref_n.ply --json -q");
  ASSERT_EQ(run.code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  EXPECT_EQ(j["reproduces"], "MPEG pc_error 0.14.2 (MPEGGroup/mpeg-pcc-dmetric @ bd6df59)");
  EXPECT_NE(version.out.find(j["commit"].get<std::string>()), std::string::npos);
}

TEST_F(PsnrCli, CsvHasTheNamedValueColumns) {
  const auto run = qm3d("psnr reference/mpeg/vox1_ref_n.ply reference/mpeg/vox1_ref_n.ply --csv");
  ASSERT_EQ(run.code, 0) << run.err;
  std::istringstream lines(run.out);
  std::string header, row;
  std::getline(lines, header);
  std::getline(lines, row);
  EXPECT_NE(header.find(",d1_mse,d1_psnr,"), std::string::npos) << header;
  EXPECT_NE(header.find(",ref_to_dist_c2_hausdorff_psnr"), std::string::npos) << header;
  EXPECT_NE(row.find(",psnr,inf,ok,"), std::string::npos) << row;
}

TEST_F(PsnrCli, CompareOnTwoCloudsListsPsnr) {
  const auto run = qm3d("compare reference/mpeg/vox1_ref_n.ply reference/voxel/vox1_requant8.ply "
                        "--peak 1023 --json -q");
  ASSERT_EQ(run.code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  ASSERT_TRUE(j["metrics"].contains("psnr"));
  ASSERT_TRUE(j["metrics"].contains("pcqm"));
  EXPECT_NEAR(j["metrics"]["psnr"]["score"].get<double>(), 58.1417823, 1e-6);
}

TEST_F(PsnrCli, BatchWritesTheValuesOfTheListsMetrics) {
  const std::string d = test::reference_dir().string();
  std::ofstream(path("list.csv")) << "reference,distorted,metric\n"
                                  << d << "/mpeg/vox1_ref_n.ply," << d
                                  << "/voxel/vox1_requant8.ply,psnr\n";
  const auto run = qm3d("batch list.csv -o out.csv -q --peak 1023", dir_);
  ASSERT_EQ(run.code, 0) << run.err;
  std::ifstream in(path("out.csv"));
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  EXPECT_NE(header.find(",d1_psnr,"), std::string::npos) << header;
  EXPECT_NE(header.find(",settings"), std::string::npos) << header;
  EXPECT_NE(row.find(",58.14178230"), std::string::npos) << row;
  // A resumed run with the same list keeps the file; the columns are the same.
  const auto again = qm3d("batch list.csv -o out.csv -q --peak 1023 --resume", dir_);
  EXPECT_EQ(again.code, 0) << again.err;
}

TEST_F(PsnrCli, MapHoldsEachPointsD1AndColourErrors) {
  const auto run = qm3d("psnr reference/mpeg/vox1_ref_n.ply reference/voxel/vox1_requant8.ply "
                        "--peak 1023 --direction ref-to-dist -q --json --map " + path("map.ply"));
  ASSERT_EQ(run.code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  const std::string bytes = test::slurp(path("map.ply"));
  for (const char* p : {"property float quality", "property float scalar_distortion",
                        "property float scalar_d2", "property float scalar_c0",
                        "property float scalar_c2"}) {
    EXPECT_NE(bytes.find(p), std::string::npos) << p;
  }
  const ply::Content map = ply::parse(bytes, "map.ply");
  EXPECT_EQ(map.positions.size(), 56320u);  // the reference's points, in its order
  EXPECT_NE(bytes.find("element vertex 56320"), std::string::npos);
  (void)j;
}

TEST_F(PsnrCli, BadInputIsOneLineNamingTheFile) {
  ply::WriteData w;
  w.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  ply::write(path("plain.ply"), w);
  w.colors = {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}};
  ply::write(path("coloured.ply"), w);
  const auto no_colour = qm3d("psnr coloured.ply plain.ply --peak 1", dir_);
  EXPECT_EQ(no_colour.code, 2);
  EXPECT_NE(no_colour.err.find("plain.ply: no vertex colours"), std::string::npos) << no_colour.err;
  EXPECT_NE(no_colour.err.find("--no-color"), std::string::npos) << no_colour.err;
  EXPECT_EQ(qm3d("psnr coloured.ply plain.ply --peak 1 --no-color", dir_).code, 0);

  // A normals file of another length, and one with a NaN normal.
  std::ofstream(path("short_n.ply")) << "ply\nformat ascii 1.0\nelement vertex 2\n"
                                        "property float x\nproperty float y\nproperty float z\n"
                                        "property float nx\nproperty float ny\nproperty float nz\n"
                                        "end_header\n0 0 0 0 0 1\n1 0 0 0 0 1\n";
  const auto short_n = qm3d("psnr coloured.ply coloured.ply --peak 1 --normals short_n.ply", dir_);
  EXPECT_EQ(short_n.code, 2);
  EXPECT_NE(short_n.err.find("short_n.ply: 2 points"), std::string::npos) << short_n.err;
  std::ofstream(path("nan_n.ply")) << "ply\nformat ascii 1.0\nelement vertex 3\n"
                                      "property float x\nproperty float y\nproperty float z\n"
                                      "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                                      "property float nx\nproperty float ny\nproperty float nz\n"
                                      "end_header\n0 0 0 1 2 3 0 0 1\n1 0 0 4 5 6 nan 0 1\n"
                                      "0 1 0 7 8 9 0 0 1\n";
  const auto nan_n = qm3d("psnr nan_n.ply coloured.ply --peak 1", dir_);
  EXPECT_EQ(nan_n.code, 2);
  EXPECT_NE(nan_n.err.find("nan_n.ply: the normal of point 1 is not finite"), std::string::npos)
      << nan_n.err;
  EXPECT_EQ(std::count(nan_n.err.begin(), nan_n.err.end(), '\n'), 1) << nan_n.err;
}

}  // namespace
}  // namespace qm3d
