// `qm3d pointssim` end to end (issue 41): every value of the reference table from the tool's
// JSON, identity, the same output on 1 and 2 threads, batch with its options (--neighbours
// shared with psnr's), the per-point map, and bad input refused with one line naming the file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.h"
#include "pointcloud/pointssim_reference.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;

class PointssimCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_pointssim_cli_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "io");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs in the reference data's folder.
  test::CliRun qm3d(const std::string& args) {
    return test::run_qm3d(args, test::pointssim_dir(), dir_ / "io");
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

nlohmann::json json_of(const test::CliRun& run) {
  EXPECT_EQ(run.code, 0) << run.err;
  return nlohmann::json::parse(run.out);
}

std::string fit_args(const test::PointssimRow& row) {
  return (row.field("fit_method") == "knn" ? " --fit-knn " : " --fit-radius ") +
         row.field("fit_size");
}

constexpr const char* kAll = " --estimators all --poolings all --attributes all";

TEST_F(PointssimCli, JsonHasEveryReferenceValue) {
  for (const test::PointssimRow& row : test::pointssim_rows()) {
    SCOPED_TRACE(row.field("case") + " K " + row.field("K"));
    const nlohmann::json j =
        json_of(qm3d("pointssim " + row.field("fileA") + " " + row.field("fileB") + fit_args(row) +
                     " --neighbours " + row.field("K") + kAll + " --json -q"));
    EXPECT_EQ(j["metric"], "pointssim");
    EXPECT_EQ(j["reproduces"], "mmspg/pointssim @ 2358dd3");
    for (const test::PointssimColumn& c : test::pointssim_columns(row)) {
      if (!test::pointssim_checked(row, c)) continue;
      const nlohmann::json& where = c.direction == "Sym" ? j["features"]
                                    : c.direction == "BA"
                                        ? j["directions"]["dist_to_ref"]["features"]
                                        : j["directions"]["ref_to_dist"]["features"];
      ASSERT_TRUE(where.contains(c.name)) << c.column;
      const double expected = std::stod(row.field(c.column));
      EXPECT_TRUE(test::pointssim_agrees(where[c.name].get<double>(), expected))
          << c.column << ": " << where[c.name] << " vs " << expected;
    }
  }
}

TEST_F(PointssimCli, IdentityTextAndThreads) {
  const auto same = qm3d("pointssim sphere_2k_ref.ply sphere_2k_ref.ply --fit-knn 12");
  ASSERT_EQ(same.code, 0) << same.err;
  EXPECT_EQ(same.out.rfind("POINTSSIM = 1  ", 0), 0u) << same.out;
  EXPECT_NE(same.out.find("[color_var_mean; 1 = identical]"), std::string::npos) << same.out;
  const std::string args =
      "pointssim vox1crop_ref.ply vox1crop_requant8.ply --fit-radius 3 --json -q" +
      std::string(kAll);
  nlohmann::json one = json_of(qm3d(args + " --threads 1"));
  nlohmann::json two = json_of(qm3d(args + " --threads 2"));
  one.erase("seconds");
  two.erase("seconds");
  EXPECT_EQ(one.dump(), two.dump());
  EXPECT_EQ(one["score_value"], "color_var_mean");
  EXPECT_EQ(one["fit"]["method"], "radius");
}

TEST_F(PointssimCli, BatchTakesItsOptionsAndMapIsPerPoint) {
  const std::string dir = test::pointssim_dir().string();
  std::ofstream(path("list.csv")) << "reference,distorted,metric\n"
                                  << dir << "/sphere_2k_ref.ply," << dir
                                  << "/sphere_2k_gnoise0.005.ply,pointssim\n";
  const auto batch = qm3d("batch " + path("list.csv") + " -o " + path("out.csv") +
                          " -q --fit-knn 12 --neighbours 6");
  ASSERT_EQ(batch.code, 0) << batch.err << test::slurp(path("out.csv"));
  const nlohmann::json alone = json_of(
      qm3d("pointssim sphere_2k_ref.ply sphere_2k_gnoise0.005.ply --fit-knn 12 --neighbours 6 "
           "--json --map " +
           path("map.ply")));
  const std::string csv = test::slurp(path("out.csv"));
  // The batch CSV and the JSON both write the shortest text that reads back the same double.
  const std::string score = ",pointssim," + alone["score"].dump() + ",ok";
  EXPECT_NE(csv.find(score), std::string::npos) << csv << "\n" << score;
  EXPECT_NE(csv.find(",geom_var_mean,"), std::string::npos);
  EXPECT_TRUE(fs::exists(path("map.ply")));
  // The single-metric command takes --neighbours above psnr's range too.
  EXPECT_EQ(alone["options"]["neighbours"], 6);
}

TEST_F(PointssimCli, BadInputIsOneLineNamingTheFile) {
  std::ofstream(path("plain.ply")) << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
                                      "property float y\nproperty float z\nend_header\n"
                                      "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  auto run = qm3d("pointssim sphere_2k_ref.ply " + path("plain.ply") + " --fit-knn 12 -q");
  EXPECT_EQ(run.code, 2);
  EXPECT_NE(run.err.find("plain.ply: 4 distinct points; pointssim needs at least 12"),
            std::string::npos)
      << run.err;
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
  run = qm3d("pointssim sphere_2k_ref.ply " + path("plain.ply") +
             " --attributes color --neighbours 3 -q");
  EXPECT_EQ(run.code, 2);
  EXPECT_NE(run.err.find("plain.ply: no colours"), std::string::npos) << run.err;
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
  run = qm3d("pointssim sphere_2k_ref.ply sphere_2k_ref.ply -q");
  EXPECT_NE(run.code, 0);
  EXPECT_NE(run.err.find("default fit radius"), std::string::npos) << run.err;
  run = qm3d("pointssim sphere_2k_ref.ply sphere_2k_ref.ply --fit-knn 6 --fit-radius 1 -q");
  EXPECT_NE(run.code, 0);
  EXPECT_NE(run.err.find("give one of them"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace qm3d
