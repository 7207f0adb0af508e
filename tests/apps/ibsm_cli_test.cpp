// `qm3d ibsm` end to end (issue 27): mmetric's rotated 1024² case from the tool's JSON, the
// rotation given as three words or one list, saved views, a mesh against a cloud, the report's
// view pairs, and bad requests refused with one line.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "cli_runner.h"
#include "mpeg_reference.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;

class IbsmCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_ibsm_cli_") +
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

const std::string kMonkey = "reference/cmdm/monkey2.obj";
const std::string kSimplified = "reference/cmdm/monkey_simplified.obj";

/// The row of mm_ibsm_reference.csv named `name`, as column -> text.
std::map<std::string, std::string> reference_row(const std::string& name) {
  for (const test::PcErrorCase& c : test::mpeg_cases("mm_ibsm_reference.csv")) {
    if (c.name == name) return c.column;
  }
  return {};
}

void expect_row(const nlohmann::json& features, const std::map<std::string, std::string>& row) {
  ASSERT_FALSE(row.empty());
  int checked = 0;
  for (const auto& [column, text] : row) {
    std::string name = column;
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (name == "unmatchedpixelpercentage") name = "unmatched_pixel_percentage";
    if (!features.contains(name)) continue;
    const double want = std::stod(text), got = features[name].get<double>();
    EXPECT_LE(std::abs(got - want), 1e-6 * std::abs(want)) << column << ": " << got << " vs " << want;
    ++checked;
  }
  EXPECT_EQ(checked, 19);
}

TEST_F(IbsmCli, MmetricsRotatedCaseFromTheToolsJson) {
  const auto row = reference_row("mm_ibsm_monkey_r1024_c6_rot");
  for (const std::string rotation : {"30 60 45", "30,60,45"}) {
    const auto run = qm3d("ibsm " + kMonkey + " " + kSimplified +
                          " --resolution 1024 --views 6 --rotation " + rotation + " --no-ssim --json");
    ASSERT_EQ(run.code, 0) << run.err;
    const nlohmann::json j = nlohmann::json::parse(run.out);
    expect_row(j["features"], row);
    EXPECT_EQ(j["score"], j["features"]["yuv_psnr"]);
    EXPECT_EQ(j["options"]["rotation"], nlohmann::json::array({30.0, 60.0, 45.0}));
    EXPECT_EQ(j["views"].size(), 6u);
    EXPECT_FALSE(j["features"].contains("ssim"));  // --no-ssim
    EXPECT_EQ(j["reproduces"], "MPEG mmetric 1.1.7 compare --mode ibsm, sw_raster (MPEGGroup/mpeg-pcc-mmetric @ 5faa660)");
  }
}

TEST_F(IbsmCli, SavesTheViewsAndScoresAMeshAgainstACloud) {
  const auto sampled = qm3d("sample " + kMonkey + " --points 100000 -o " + path("samples.ply") + " -q");
  ASSERT_EQ(sampled.code, 0) << sampled.err;
  const auto run = qm3d("ibsm " + kMonkey + " " + path("samples.ply") +
                        " --resolution 256 --views 4 --save-views " + path("views") + " --json");
  ASSERT_EQ(run.code, 0) << run.err;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  EXPECT_GT(j["score"].get<double>(), 30.0);
  EXPECT_LT(j["score"].get<double>(), 99.99);
  EXPECT_GT(j["features"]["ssim"].get<double>(), 0.5);
  EXPECT_GT(j["splat_size_distorted"].get<double>(), 0.0);
  for (int i = 0; i < 4; ++i) {
    EXPECT_TRUE(fs::exists(dir_ / "views" / ("view_0" + std::to_string(i) + "_reference.png")));
    EXPECT_TRUE(fs::exists(dir_ / "views" / ("view_0" + std::to_string(i) + "_distorted.png")));
  }
}

TEST_F(IbsmCli, TheReportShowsTheViewPairs) {
  const auto run = qm3d("ibsm " + kMonkey + " " + kSimplified +
                        " --resolution 256 --views 3 --no-ssim --report " + path("r.html") + " -q");
  ASSERT_EQ(run.code, 0) << run.err;
  const std::string html = test::slurp(dir_ / "r.html");
  EXPECT_NE(html.find("data:image/png;base64,"), std::string::npos);
}

TEST_F(IbsmCli, BadRequestsAreRefusedWithOneLine) {
  struct Case {
    std::string args;
    int code;
    std::string says;
  };
  const std::vector<Case> cases = {
      {"--rotation 30 60", 1, "rotation"},
      {"--layout cmdm18 --views 6", 1, "fibonacci layout"},
      {"--views 1", 1, "views"},
      {"--resolution 8", 1, "resolution"},
      {"--lighting sun", 1, "lighting"},
      {"--splat-shape star", 1, "splat-shape"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args);
    const auto run = qm3d("ibsm " + kMonkey + " " + kSimplified + " " + c.args);
    EXPECT_EQ(run.code, c.code) << run.err;
    EXPECT_NE(run.err.find(c.says), std::string::npos) << run.err;
    EXPECT_TRUE(run.out.empty());
  }
  const auto missing = qm3d("ibsm " + kMonkey + " " + path("nothing.ply"));
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.err.find("nothing.ply"), std::string::npos) << missing.err;
  // A directory the views cannot be written to.
  std::ofstream(path("file")) << "x";
  const auto unwritable = qm3d("ibsm " + kMonkey + " " + kSimplified +
                               " --resolution 64 --views 2 --save-views " + path("file") + "/sub");
  EXPECT_EQ(unwritable.code, 2) << unwritable.err;
  EXPECT_NE(unwritable.err.find("file"), std::string::npos) << unwritable.err;
}

}  // namespace
}  // namespace qm3d
