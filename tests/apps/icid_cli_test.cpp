// `qm3d image` and `qm3d icid` end to end (issue 40): every synthetic row of the iCID reference
// table (tests/icid_reference.h) from the tool's JSON, the 18-view means from `qm3d icid` on the
// reference's stimuli (rendered again: the same views), the per-pixel map, and bad images refused
// with one line naming the file.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "cli_runner.h"
#include "icid_reference.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;
using test::icid_close;
using test::icid_dir;

class IcidCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_icid_cli_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  test::CliRun run(const std::string& args) const {
    return test::run_qm3d(args + " --data-dir '" + test::tables_dir().string() + "'", icid_dir(),
                          dir_);
  }

  fs::path dir_;
};

std::string quoted(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += " " + w;
  return out;
}

std::array<double, 8> values_of(const nlohmann::json& features) {
  std::array<double, 8> v{};
  v[0] = features.at("icid").get<double>();
  for (int k = 1; k <= 7; ++k) v[k] = features.at("icid_m" + std::to_string(k)).get<double>();
  return v;
}

// Every synthetic row (every option); the view rows through `qm3d icid` below (their means), and
// one by one in the library's test (tests/render/icid_test.cpp): 54 more runs of the tool would
// add a minute to the suite and test nothing the JSON rows here do not.
TEST_F(IcidCli, EverySyntheticRowFromTheJson) {
  std::vector<test::IcidCase> rows;
  for (const auto& c : test::icid_cases()) {
    if (c.set().empty() && !test::icid_row_read_differently(c.name)) rows.push_back(c);
  }
  ASSERT_EQ(rows.size(), 54u);  // synth_colour_bars: tests/render/icid_test.cpp, test_icid.py
  // The runs spread over the cores, each with its own output files and one thread.
  std::vector<test::CliRun> runs(rows.size());
  std::atomic<std::size_t> next{0};
  const auto work = [&](int worker) {
    const fs::path io = dir_ / ("worker" + std::to_string(worker));
    fs::create_directories(io);
    for (std::size_t i = next++; i < rows.size(); i = next++) {
      runs[i] = test::run_qm3d("image " + rows[i].image_a + " " + rows[i].image_b +
                                   " --json --threads 1" +
                                   quoted(test::icid_cli_options(rows[i].options)) +
                                   " --data-dir '" + test::tables_dir().string() + "'",
                               icid_dir(), io);
    }
  };
  std::vector<std::thread> workers(std::max(2u, std::thread::hardware_concurrency()) - 1);
  for (std::size_t w = 0; w < workers.size(); ++w) workers[w] = std::thread(work, w + 1);
  work(0);
  for (auto& w : workers) w.join();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& c = rows[i];
    ASSERT_EQ(runs[i].code, 0) << c.name << ": " << runs[i].err;
    const auto j = nlohmann::json::parse(runs[i].out);
    EXPECT_EQ(j.at("score").get<double>(), j.at("features").at("icid").get<double>());
    const auto got = values_of(j.at("features"));
    for (int k = 0; k < 8; ++k) {
      EXPECT_PRED2(icid_close, got[k], c.values[k]) << c.name << " " << c.options << " " << k;
    }
  }
}

TEST_F(IcidCli, MetricOnTheStimuliGivesThe18ViewMeans) {
  for (const auto& c : test::icid_cases()) {
    if (!c.is_mean()) continue;
    const fs::path stimuli = test::reference_dir() / "cmdm";
    const auto r = run("icid '" + (stimuli / "blob4_ref.off").string() + "' '" +
                       (stimuli / (c.set() + ".off")).string() + "' --json");
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j.at("views").size(), 18u);
    const auto got = values_of(j.at("features"));
    for (int k = 0; k < 8; ++k) {
      EXPECT_PRED2(icid_close, got[k], c.values[k]) << c.name << " " << k;
    }
  }
}

TEST_F(IcidCli, HumanLineCsvAndMap) {
  const std::string pair = " synth/synth_blur_a.png synth/synth_blur_b.png";
  const auto text = run("image" + pair);
  ASSERT_EQ(text.code, 0) << text.err;
  EXPECT_NE(text.out.find("iCID = 0.18377"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("MS-SSIM"), std::string::npos);
  const auto csv = run("image" + pair + " --csv");
  ASSERT_EQ(csv.code, 0) << csv.err;
  EXPECT_NE(csv.out.find(",icid,icid_m1,"), std::string::npos) << csv.out;
  const fs::path map = dir_ / "map.npy";
  const auto with_map = run("image" + pair + " --map '" + map.string() + "'");
  ASSERT_EQ(with_map.code, 0) << with_map.err;
  const std::string npy = test::slurp(map);
  ASSERT_GT(npy.size(), 128u);
  EXPECT_EQ(npy.substr(1, 5), "NUMPY");
  EXPECT_NE(npy.find("'shape': (182, 246)"), std::string::npos);  // 192 x 256 less 5 a side
  EXPECT_EQ(npy.size() % 64, (182u * 246u * 8u) % 64);
}

TEST_F(IcidCli, IdenticalImagesScoreZero) {
  const auto r = run("image synth/synth_noise_a.png synth/synth_noise_a.png --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_LE(std::abs(nlohmann::json::parse(r.out).at("score").get<double>()), 1e-13);
}

TEST_F(IcidCli, BadImagesOneLineNamingTheFile) {
  const fs::path text = dir_ / "notes.png", empty = dir_ / "empty.jpg";
  std::ofstream(text) << "not an image\n";
  std::ofstream(empty).flush();
  const std::string good = "synth/synth_blur_a.png";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"image " + good + " missing.png", "missing.png"},
      {"image '" + text.string() + "' " + good, text.string()},
      {"image " + good + " '" + empty.string() + "'", empty.string()},
      {"image " + good + " synth/synth_noise_a.png", "synth/synth_noise_a.png"},
  };
  for (const auto& [args, named] : cases) {
    const auto r = run(args);
    EXPECT_NE(r.code, 0) << args;
    EXPECT_NE(r.err.find(named), std::string::npos) << args << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
}

}  // namespace
}  // namespace qm3d
