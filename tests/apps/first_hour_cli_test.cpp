// A new user's first hour (issue 44): --help that fits the terminal, batch results people can
// read (the value columns of the metrics that ran, rows in list order, a warnings column).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "cli_runner.h"
#include "qm3d/common/result_io.h"
#include "qm3d/study/batch_row.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;
using test::CliRun;
using test::slurp;

class FirstHour : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_first_hour_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "io");
  }
  void TearDown() override { fs::remove_all(dir_); }

  CliRun qm3d(const std::string& args, const std::string& env = "") {
    return test::run_qm3d(args, dir_, dir_ / "io",
                          "QM3D_DATA_DIR='" + test::tables_dir().string() + "' " + env);
  }

  fs::path dir_;
};

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// Characters, not bytes (the help has a few in UTF-8: arrows, "≥").
std::size_t characters(const std::string& s) {
  std::size_t n = 0;
  for (unsigned char c : s) n += (c & 0xC0) != 0x80;
  return n;
}

std::multiset<std::string> words(const std::string& text) {
  std::multiset<std::string> out;
  std::istringstream in(text);
  for (std::string w; in >> w;) out.insert(w);
  return out;
}

// The commands `qm3d --help` lists.
std::vector<std::string> commands(const std::string& help) {
  std::vector<std::string> names;
  bool in_list = false;
  for (const std::string& line : lines_of(help)) {
    if (line.rfind("Subcommands:", 0) == 0 || line.rfind("SUBCOMMANDS:", 0) == 0) {
      in_list = true;
    } else if (in_list && line.size() > 2 && line.rfind("  ", 0) == 0 && line[2] != ' ') {
      names.push_back(line.substr(2, line.find(' ', 2) - 2));
    }
  }
  return names;
}

// Every command's --help fits COLUMNS=100 and loses no word (option, type, default) against
// an unlimited width; batch's metric options are grouped under their metric.
TEST_F(FirstHour, HelpIsWrappedToTheTerminalWidthAndKeepsEveryOption) {
  const CliRun top = qm3d("--help", "COLUMNS=100");
  ASSERT_EQ(top.code, 0) << top.err;
  const std::vector<std::string> names = commands(top.out);
  ASSERT_GE(names.size(), 10u) << top.out;
  std::vector<std::string> all = {""};
  all.insert(all.end(), names.begin(), names.end());
  for (const std::string& name : all) {
    const CliRun narrow = qm3d(name + " --help", "COLUMNS=100");
    const CliRun wide = qm3d(name + " --help", "COLUMNS=100000");
    ASSERT_EQ(narrow.code, 0) << name << ": " << narrow.err;
    for (const std::string& line : lines_of(narrow.out)) {
      EXPECT_LE(characters(line), 100u) << name << ": " << line;
    }
    EXPECT_EQ(words(narrow.out), words(wide.out)) << name;
  }
  const CliRun batch = qm3d("batch --help", "COLUMNS=100");
  EXPECT_NE(batch.out.find("Options of PCQM (pcqm):"), std::string::npos) << batch.out;
  EXPECT_NE(batch.out.find("--knn"), std::string::npos);
  // Not a terminal and no COLUMNS: 80.
  const CliRun plain = qm3d("batch --help", "env -u COLUMNS");
  for (const std::string& line : lines_of(plain.out)) EXPECT_LE(characters(line), 80u) << line;
}

std::string mesh(const std::string& name) {
  return (fs::path(QM3D_SOURCE_DIR) / "data" / "meshes" / name).string();
}

// The header's columns.
std::vector<std::string> header_of(const std::string& results) {
  return csv_split(lines_of(results).front());
}

// A mesh-only batch with `compare`: only the value columns of the metrics that ran (none of
// the point-cloud metrics'), rows in list order whatever order they were scored in (a resume
// appends), a warnings column; resuming the tidy file works.
TEST_F(FirstHour, BatchResultsHaveTheRunsColumnsInListOrder) {
  const fs::path list = dir_ / "list.csv", out = dir_ / "results.csv";
  std::ofstream(list) << "reference,distorted,metric\n"
                      << mesh("blob3_ref.off") << "," << mesh("blob3_colnoise.off") << ",cmdm\n";
  ASSERT_EQ(qm3d("batch " + list.string() + " -o " + out.string() + " -q").code, 0);
  // The list grows at the front: the first run's row was written first, but is second in it.
  std::ofstream(list) << "reference,distorted,metric\n"
                      << mesh("blob3_ref.off") << "," << mesh("blob3_geonoise.off") << ",compare\n"
                      << mesh("blob3_ref.off") << "," << mesh("blob3_colnoise.off") << ",cmdm\n";
  const CliRun resumed = qm3d("batch " + list.string() + " -o " + out.string() + " -q --resume");
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  const std::string results = slurp(out);
  const auto header = header_of(results);
  const std::set<std::string> columns(header.begin(), header.end());
  EXPECT_TRUE(columns.count("warnings"));
  EXPECT_EQ(header.back(), "settings");
  // Every value column has a value in some row: no column of a metric that did not run.
  const auto rows = lines_of(results);
  for (std::size_t c = csv_split(study::csv_header()).size(); c + 1 < header.size(); ++c) {
    bool any = false;
    for (std::size_t r = 1; r < rows.size(); ++r) any = any || !csv_split(rows[r])[c].empty();
    EXPECT_TRUE(any) << "empty column " << header[c];
  }
  EXPECT_FALSE(columns.count("d1_mse")) << "a point-cloud metric's column";  // psnr's
  ASSERT_GE(rows.size(), 4u);
  EXPECT_NE(rows[1].find("blob3_geonoise"), std::string::npos) << results;
  EXPECT_NE(rows.back().find("blob3_colnoise"), std::string::npos) << results;
  // Resume of the tidy file: nothing to do, the file unchanged.
  const CliRun again = qm3d("batch " + list.string() + " -o " + out.string() + " -q --resume");
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_EQ(slurp(out), results);
}

// Shards keep the full header (merge requires one header); the merged file is tidy.
TEST_F(FirstHour, MergedShardsAreTidyToo) {
  const fs::path list = dir_ / "list.csv";
  std::ofstream(list) << "reference,distorted,metric\n"
                      << mesh("blob3_ref.off") << "," << mesh("blob3_geonoise.off") << ",cmdm\n"
                      << mesh("blob3_ref.off") << "," << mesh("blob3_colnoise.off") << ",compare\n";
  std::string shards;
  for (int k = 0; k < 2; ++k) {
    const fs::path out = dir_ / ("shard" + std::to_string(k) + ".csv");
    ASSERT_EQ(qm3d("batch " + list.string() + " -o " + out.string() + " -q --shard " +
                   std::to_string(k) + "/2")
                  .code,
              0);
    EXPECT_TRUE(header_of(slurp(out)) == header_of(slurp(dir_ / "shard0.csv")));
    shards += " " + out.string();
  }
  const fs::path merged = dir_ / "merged.csv";
  const CliRun m =
      qm3d("merge --list " + list.string() + shards + " -o " + merged.string() + " -q");
  ASSERT_EQ(m.code, 0) << m.err;
  const auto header = header_of(slurp(merged));
  EXPECT_LT(header.size(), header_of(slurp(dir_ / "shard0.csv")).size());
  EXPECT_EQ(std::count(header.begin(), header.end(), "d1_mse"), 0);
  const auto rows = lines_of(slurp(merged));
  ASSERT_GE(rows.size(), 3u);
  EXPECT_NE(rows[1].find("blob3_geonoise"), std::string::npos);
}

// The warnings column holds each row's count of warnings and the first one, as `--json` has them.
TEST_F(FirstHour, BatchWarningsColumnHasTheCountAndFirstMessage) {
  const std::string ref =
      (fs::path(QM3D_SOURCE_DIR) / "data" / "clouds" / "sphere_2k_ref.ply").string();
  const std::string dist =
      (fs::path(QM3D_SOURCE_DIR) / "data" / "clouds" / "sphere_2k_gnoise0.005.ply").string();
  const fs::path list = dir_ / "list.csv", out = dir_ / "results.csv";
  std::ofstream(list) << "reference,distorted,metric\n" << ref << "," << dist << ",psnr\n";
  ASSERT_EQ(qm3d("batch " + list.string() + " -o " + out.string() + " -q").code, 0);
  const CliRun single = qm3d("psnr " + ref + " " + dist + " --json");
  ASSERT_EQ(single.code, 0) << single.err;
  const auto warnings = nlohmann::json::parse(single.out)["warnings"];
  const std::string expected =
      warnings.empty() ? ""
                       : std::to_string(warnings.size()) + ": " + warnings[0].get<std::string>();
  const auto rows = lines_of(slurp(out));
  const auto header = header_of(slurp(out));
  const auto column = std::find(header.begin(), header.end(), "warnings") - header.begin();
  ASSERT_LT(static_cast<std::size_t>(column), header.size());
  EXPECT_EQ(csv_split(rows.at(1))[static_cast<std::size_t>(column)], expected);
}


// Batch progress counts rows (a pair and a metric) and pairs apart: 2 pairs of 2 rows each end
// on "4/4 rows, 2/2 pairs"; a list of one row per pair says pairs only.
TEST_F(FirstHour, BatchProgressCountsRowsAndPairsApart) {
  const std::string ref =
      (fs::path(QM3D_SOURCE_DIR) / "data" / "clouds" / "sphere_2k_ref.ply").string();
  const std::string d1 =
      (fs::path(QM3D_SOURCE_DIR) / "data" / "clouds" / "sphere_2k_gnoise0.005.ply").string();
  const std::string d2 =
      (fs::path(QM3D_SOURCE_DIR) / "data" / "clouds" / "sphere_2k_cnoise10.ply").string();
  const fs::path list = dir_ / "list.csv", out = dir_ / "results.csv";
  std::ofstream(list) << "reference,distorted,metric\n"
                      << ref << "," << d1 << ",psnr\n" << ref << "," << d1 << ",dlab\n"
                      << ref << "," << d2 << ",psnr\n" << ref << "," << d2 << ",dlab\n";
  const CliRun two = qm3d("batch " + list.string() + " -o " + out.string());
  ASSERT_EQ(two.code, 0) << two.err;
  EXPECT_NE(two.err.find("batch: 4/4 rows, 2/2 pairs done (0 failed)"), std::string::npos)
      << two.err;
  std::ofstream(list) << "reference,distorted,metric\n"
                      << ref << "," << d1 << ",psnr\n" << ref << "," << d2 << ",psnr\n";
  const CliRun one = qm3d("batch " + list.string() + " -o " + out.string() + " --overwrite");
  ASSERT_EQ(one.code, 0) << one.err;
  EXPECT_NE(one.err.find("batch: 2/2 pairs done (0 failed)"), std::string::npos) << one.err;
}

}  // namespace
}  // namespace qm3d
