// `qm3d graphsim` / `qm3d msgraphsim` end to end (issue 42): the reference table's smA values
// through the tool's options (--keypoint-file, --pooling-weights, --threshold, --scales), the
// per-keypoint map, batch with a keypoint file, and bad inputs refused with one line naming the
// file or the cause.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli_runner.h"
#include "qm3d/common/ply.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;

constexpr double kTolerance = 1e-10;  // relative, the acceptance

class GraphsimCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_graphsim_cli_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "io");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs in the reference data's directory (its clouds and keypoint files by relative name).
  test::CliRun qm3d(const std::string& args) {
    return test::run_qm3d(args, data(), dir_ / "io",
                          "QM3D_DATA_DIR='" + test::tables_dir().string() + "'");
  }
  static fs::path data() { return test::reference_dir() / "graphsim"; }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

/// The reference table's row of a case as {column: text}.
std::map<std::string, std::string> reference_case(const std::string& name) {
  std::ifstream in(test::reference_dir() / "graphsim" / "graphsim_reference.csv");
  std::string line;
  std::vector<std::string> header;
  const auto split = [](const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ';')) out.push_back(item);
    return out;
  };
  std::getline(in, line);
  header = split(line);
  while (std::getline(in, line)) {
    const auto items = split(line);
    if (items.empty() || items[0] != name) continue;
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < items.size(); ++i) row[header[i]] = items[i];
    return row;
  }
  return {};
}

nlohmann::json json_of(const test::CliRun& run) {
  EXPECT_EQ(run.code, 0) << run.err;
  return nlohmann::json::parse(run.out.empty() ? "{}" : run.out);
}

void expect_near(double got, const std::string& want_text, const std::string& what) {
  const double want = std::stod(want_text);
  EXPECT_LE(std::abs(got - want), kTolerance * std::abs(want)) << what << ": " << got;
}

constexpr const char* kPair = "smA_ref.ply smA_octree2.ply --keypoint-file keys_smA_ref.txt";

TEST_F(GraphsimCli, OptionsReproduceTheReferenceTable) {
  const auto want = reference_case("smA_octree2");
  ASSERT_FALSE(want.empty());
  const nlohmann::json g = json_of(qm3d(std::string("graphsim ") + kPair + " --json"));
  EXPECT_EQ(g["metric"], "graphsim");
  expect_near(g["score"].get<double>(), want.at("graphsim"), "graphsim");
  EXPECT_EQ(g["keypoints"].get<int>(), 40);
  EXPECT_EQ(g["epsilon"].get<double>(), 5.0);
  EXPECT_EQ(g["keypoint_rows"].size(), 40u);
  expect_near(
      json_of(qm3d(std::string("graphsim ") + kPair + " --pooling-weights 1,1,1 --json"))["score"]
          .get<double>(),
      want.at("graphsim_w111"), "w111");
  expect_near(json_of(qm3d(std::string("graphsim ") + kPair + " --threshold 0.01 --json"))["score"]
                  .get<double>(),
              want.at("graphsim_T0.01"), "T0.01");
  expect_near(json_of(qm3d(std::string("msgraphsim ") + kPair + " --json"))["score"].get<double>(),
              want.at("msgraphsim"), "msgraphsim");
  const nlohmann::json ms6 =
      json_of(qm3d(std::string("msgraphsim ") + kPair + " --scales 6 --json"));
  expect_near(ms6["score"].get<double>(), want.at("msgraphsim_ns6"), "ns6");
  for (int k = 0; k < 6; ++k) {
    const std::string s = std::to_string(k);
    expect_near(ms6["features"]["scale" + s].get<double>(), want.at("ms_scale" + s), "scale" + s);
  }
}

TEST_F(GraphsimCli, SelfIsOneAndTheTextLineSaysTheKeypoints) {
  const auto run = qm3d("graphsim smA_ref.ply smA_ref.ply --keypoint-file keys_smA_ref.txt");
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_EQ(run.out.rfind("GRAPHSIM = 1  (ref→dist)  [40 keypoints, eps 5]", 0), 0u) << run.out;
}

TEST_F(GraphsimCli, MapHoldsTheKeypointScoresOnTheirPositions) {
  const auto run = qm3d(std::string("msgraphsim ") + kPair + " --map " + path("map.ply") + " -q");
  ASSERT_EQ(run.code, 0) << run.err;
  const ply::Content map = ply::read(path("map.ply"));
  const ply::Content ref = ply::read(data() / "smA_ref.ply");
  std::ifstream keys(data() / "keys_smA_ref.txt");
  std::size_t row = 0, k = 0;
  while (keys >> row) {
    ASSERT_LT(k, map.positions.size());
    EXPECT_EQ(map.positions[k], ref.positions[row]) << k;
    ++k;
  }
  EXPECT_EQ(map.positions.size(), 40u);
}

TEST_F(GraphsimCli, ReportIsWrittenWithoutAHeatMap) {
  const auto run =
      qm3d(std::string("msgraphsim ") + kPair + " --report " + path("report.html") + " -q");
  ASSERT_EQ(run.code, 0) << run.err;
  const std::string html = test::slurp(path("report.html"));
  EXPECT_NE(html.find("msgraphsim"), std::string::npos);
}

TEST_F(GraphsimCli, BatchTakesTheKeypointFile) {
  const std::string d = data().string();
  std::ofstream(path("list.csv")) << "reference,distorted,metric\n"
                                  << d << "/smA_ref.ply," << d << "/smA_cshift.ply,graphsim\n"
                                  << d << "/smA_ref.ply," << d << "/smA_cshift.ply,msgraphsim\n";
  const auto run = qm3d("batch " + path("list.csv") + " -o " + path("out.csv") +
                        " --keypoint-file keys_smA_ref.txt -q");
  ASSERT_EQ(run.code, 0) << run.err << test::slurp(path("out.csv"));
  const std::string csv = test::slurp(path("out.csv"));
  const auto want = reference_case("smA_cshift");
  EXPECT_NE(csv.find(",graphsim," + want.at("graphsim").substr(0, 12)), std::string::npos) << csv;
  EXPECT_NE(csv.find(",msgraphsim," + want.at("msgraphsim").substr(0, 12)), std::string::npos)
      << csv;
}

TEST_F(GraphsimCli, BadInputsAreOneLineNamingTheFileOrTheCause) {
  std::ofstream(path("keys.txt")) << "0\n9048\n";
  ply::WriteData plain;
  for (int i = 0; i < 30; ++i)
    plain.positions.push_back({i * 1.0, (i * 7 % 30) * 1.0, i % 20 * 1.0});
  ply::write(path("plain.ply"), plain);
  ply::WriteData flat = plain;
  for (auto& p : flat.positions) p[2] = 0;
  flat.colors.assign(flat.positions.size(), {10, 20, 30});
  ply::write(path("flat.ply"), flat);
  const std::pair<std::string, std::string> cases[] = {
      {"graphsim smA_ref.ply smA_ref.ply --keypoint-file " + path("keys.txt"), "keys.txt: line 2"},
      {"msgraphsim smA_ref.ply " + path("plain.ply") + " --keypoint-file keys_smA_ref.txt",
       "plain.ply: no vertex colours"},
      {"graphsim " + path("flat.ply") + " " + path("flat.ply"), "radius"},
      {"graphsim smA_ref.ply smA_ref.ply --keypoint-file " + path("none.txt"), "none.txt"}};
  for (const auto& [args, want] : cases) {
    SCOPED_TRACE(args);
    const auto run = qm3d(args);
    EXPECT_NE(run.code, 0);
    EXPECT_NE(run.err.find(want), std::string::npos) << run.err;
    EXPECT_EQ(run.err.find('\n'), run.err.size() - 1) << run.err;
  }
}

}  // namespace
}  // namespace qm3d
