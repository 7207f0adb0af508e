// GraphSIM / MS-GraphSIM (pointcloud_metric/src/graphsim*.cpp) through the registry, against the
// reference data ../shared/data/reference/graphsim (the authors' MATLAB functions run in float64
// under Octave): every float64 column of every case within 1e-10 relative (a mismatch prints the
// keypoints that differ, from graphsim_reference_per_keypoint.csv), a cloud against itself
// exactly 1, the same bits on 1 and 2 threads, and one-line refusals of bad inputs.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "qm3d/common/error.h"
#include "qm3d/common/metric.h"
#include "qm3d/pointcloud/metrics.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;

constexpr double kTolerance = 1e-10;  // relative, the acceptance

const Registry& registry() {
  static const Registry r = [] {
    Registry out;
    pointcloud::register_metrics(out);
    return out;
  }();
  return r;
}

fs::path data_dir() { return test::reference_dir() / "graphsim"; }

/// The rows of a ';'-separated table as {column: text}.
std::vector<std::map<std::string, std::string>> read_table(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
  const auto split = [](const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ';')) out.push_back(item);
    return out;
  };
  if (std::getline(in, line)) header = split(line);
  while (std::getline(in, line)) {
    const auto items = split(line);
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < items.size(); ++i) row[header[i]] = items[i];
    rows.push_back(row);
  }
  return rows;
}

const std::vector<std::map<std::string, std::string>>& cases() {
  static const auto rows = read_table(data_dir() / "graphsim_reference.csv");
  return rows;
}

/// The reference's per-keypoint scores of a case and column ("graphsim_kp", "ms_scale3_kp").
std::vector<double> per_keypoint(const std::string& name, const std::string& column) {
  static const auto rows = read_table(data_dir() / "graphsim_reference_per_keypoint.csv");
  std::vector<double> out;
  for (const auto& r : rows) {
    if (r.at("case") == name) out.push_back(std::stod(r.at(column)));
  }
  return out;
}

const Input& cloud(const std::string& relative) {
  static std::map<std::string, Input> cache;
  const auto it = cache.find(relative);
  if (it != cache.end()) return it->second;
  return cache.emplace(relative, registry().read(data_dir() / relative)).first->second;
}

MetricResult run(const std::string& metric, const std::map<std::string, std::string>& c,
                 OptionValues options, int threads = 0) {
  options["keypoint_file"] = (data_dir() / c.at("keypoint_file")).string();
  RunOptions ro;
  ro.threads = threads;
  return run_metric(registry().get(metric), cloud(c.at("reference")), cloud(c.at("distorted")), ro,
                    options);
}

double relative(double got, double want) {
  return std::abs(got - want) / std::max(std::abs(want), 1e-300);
}

/// The largest relative error seen (printed by the reference tests).
double& worst_error() {
  static double worst = 0;
  return worst;
}

/// Expects `got` within the tolerance of the case's column, and each keypoint's score within it
/// of the reference's (`keypoint_column` of the per-keypoint table), listing those that differ.
void expect_column(const std::map<std::string, std::string>& c, const std::string& column,
                   double got, const std::vector<double>& got_per_keypoint,
                   const std::string& keypoint_column) {
  const double want = std::stod(c.at(column));
  const double err = relative(got, want);
  worst_error() = std::max(worst_error(), err);
  EXPECT_LE(err, kTolerance) << c.at("case") << " " << column << ": got " << got << " want "
                             << want;
  if (keypoint_column.empty()) return;
  // Every keypoint's score too (relative, or absolute for a keypoint scoring 0).
  const std::vector<double> ref = per_keypoint(c.at("case"), keypoint_column);
  EXPECT_EQ(got_per_keypoint.size(), ref.size()) << c.at("case") << " " << keypoint_column;
  for (std::size_t k = 0; k < ref.size() && k < got_per_keypoint.size(); ++k) {
    const double e =
        ref[k] == 0 ? std::abs(got_per_keypoint[k]) : relative(got_per_keypoint[k], ref[k]);
    worst_error() = std::max(worst_error(), e);
    if (e > kTolerance) {
      ADD_FAILURE() << "  keypoint " << k << ": got " << got_per_keypoint[k] << " want " << ref[k];
    }
  }
}

std::vector<double> scale_values(const MetricResult& r, int scale) {
  const DirectionResult& d = r.any_direction();
  for (const auto& [name, v] : d.per_element_values) {
    if (name == "scale" + std::to_string(scale)) return v;
  }
  return {};
}

TEST(GraphsimReference, HasThirteenCases) { EXPECT_EQ(cases().size(), 13u); }

TEST(GraphsimReference, GraphsimColumns) {
  for (const auto& c : cases()) {
    const MetricResult r = run("graphsim", c, {});
    expect_column(c, "graphsim", r.score, r.any_direction().per_element, "graphsim_kp");
    EXPECT_EQ(r.details.at("epsilon").get<double>(), std::stod(c.at("epsilon")));
    EXPECT_EQ(r.details.at("keypoints").get<int>(), std::stoi(c.at("n_keypoints")));
    const MetricResult w = run("graphsim", c, {{"pooling_weights", {1, 1, 1}}});
    expect_column(c, "graphsim_w111", w.score, {}, "");
    const MetricResult t = run("graphsim", c, {{"threshold", 0.01}});
    expect_column(c, "graphsim_T0.01", t.score, {}, "");
  }
  std::cout << "worst relative error so far: " << worst_error() << "\n";
}

TEST(GraphsimReference, MsGraphsimColumns) {
  for (const auto& c : cases()) {
    const MetricResult r = run("msgraphsim", c, {});
    expect_column(c, "msgraphsim", r.score, {}, "");
    const MetricResult r6 = run("msgraphsim", c, {{"scales", 6}});
    expect_column(c, "msgraphsim_ns6", r6.score, {}, "");
    for (int k = 0; k < 6; ++k) {
      const std::string s = "scale" + std::to_string(k);
      const double v = *find_value(r6.values, s);
      expect_column(c, "ms_scale" + std::to_string(k), v, scale_values(r6, k),
                    "ms_scale" + std::to_string(k) + "_kp");
      if (k < 3) EXPECT_EQ(v, *find_value(r.values, s)) << c.at("case") << " " << s;
    }
    EXPECT_EQ(*find_value(r6.values, "scale0"), run("graphsim", c, {}).score) << c.at("case");
  }
  std::cout << "worst relative error so far: " << worst_error() << "\n";
}

TEST(Graphsim, SelfComparisonIsExactlyOne) {
  for (const auto& c : cases()) {
    if (c.at("reference") != c.at("distorted")) continue;
    EXPECT_EQ(run("graphsim", c, {}).score, 1.0) << c.at("case");
    const MetricResult ms = run("msgraphsim", c, {{"scales", 6}});
    EXPECT_EQ(ms.score, 1.0) << c.at("case");
  }
}

TEST(Graphsim, SameBitsOnOneAndTwoThreads) {
  const auto& c = cases().at(5);  // vox1_requant9: the scale-3 ties of the README
  for (const char* metric : {"graphsim", "msgraphsim"}) {
    const OptionValues o =
        std::string(metric) == "graphsim" ? OptionValues::object() : OptionValues{{"scales", 6}};
    const MetricResult one = run(metric, c, o, 1);
    const MetricResult two = run(metric, c, o, 2);
    EXPECT_EQ(one.score, two.score) << metric;
    EXPECT_EQ(one.any_direction().per_element, two.any_direction().per_element) << metric;
  }
}

/// A cloud on a grid of `side` points per axis spaced `step` (z spaced `zstep`), coloured.
ColoredCloud grid_cloud(int side, double step, double zstep) {
  ColoredCloud c;
  for (int x = 0; x < side; ++x) {
    for (int y = 0; y < side; ++y) {
      for (int z = 0; z < 2; ++z) {
        c.positions.push_back({x * step, y * step, z * zstep});
        c.colors.push_back({x / (side - 1.0), y / (side - 1.0), z * 0.5});
      }
    }
  }
  return c;
}

std::string error_of(const std::string& metric, const Input& ref, const Input& dist,
                     const OptionValues& options) {
  try {
    run_metric(registry().get(metric), ref, dist, RunOptions{}, options);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Graphsim, KeypointOutOfRangeNamesTheFile) {
  const fs::path file = fs::temp_directory_path() / "qm3d_graphsim_bad_keys.txt";
  std::ofstream(file) << "3\n9048\n";
  const Input& ref = cloud("smA_ref.ply");
  const std::string e = error_of("graphsim", ref, ref, {{"keypoint_file", file.string()}});
  EXPECT_NE(e.find(file.string()), std::string::npos) << e;
  EXPECT_NE(e.find("line 2"), std::string::npos) << e;
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  std::ofstream(file) << "3\nseven\n";
  EXPECT_NE(error_of("msgraphsim", ref, ref, {{"keypoint_file", file.string()}}).find("seven"),
            std::string::npos);
  fs::remove(file);
}

TEST(Graphsim, CloudWithoutColourNamesTheFile) {
  ColoredCloud plain = grid_cloud(30, 1, 20);
  plain.colors.clear();
  const Input ref = Input::from_cloud(grid_cloud(30, 1, 20), "coloured.ply");
  const Input dist = Input::from_cloud(plain, "plain.ply");
  const std::string e = error_of("graphsim", ref, dist, {});
  EXPECT_NE(e.find("plain.ply"), std::string::npos) << e;
  EXPECT_NE(e.find("colour"), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
}

TEST(Graphsim, FlatBoxIsRefusedWithItsCause) {
  const Input flat = Input::from_cloud(grid_cloud(30, 1, 0), "flat.ply");
  for (const char* metric : {"graphsim", "msgraphsim"}) {
    const std::string e = error_of(metric, flat, flat, {});
    EXPECT_NE(e.find("flat.ply"), std::string::npos) << e;
    EXPECT_NE(e.find("radius"), std::string::npos) << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  }
}

TEST(Graphsim, LoneKeypointsScoreZeroWithAWarning) {
  // Points 30 apart, eps 9: no keypoint has a neighbour, cg = 0 (the reference's rule).
  const Input sparse = Input::from_cloud(grid_cloud(5, 30, 60), "sparse.ply");
  const MetricResult r =
      run_metric(registry().get("graphsim"), sparse, sparse, RunOptions{}, {{"keypoints", 3}});
  EXPECT_EQ(r.score, 0.0);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("sparse.ply: 3 of 3 keypoints"), std::string::npos) << r.warnings[0];
}

TEST(Graphsim, SeededKeypointsAreDeterministic) {
  const Input& ref = cloud("smA_ref.ply");
  const Input& dist = cloud("smA_cnoise8.ply");
  const OptionValues o{{"keypoints", 40}, {"seed", 7}};
  RunOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const MetricResult a = run_metric(registry().get("graphsim"), ref, dist, one, o);
  const MetricResult b = run_metric(registry().get("graphsim"), ref, dist, two, o);
  EXPECT_EQ(a.details.at("keypoint_rows"), b.details.at("keypoint_rows"));
  EXPECT_EQ(a.score, b.score);
  EXPECT_EQ(a.details.at("keypoints").get<int>(), 40);
  EXPECT_GT(a.score, 0.5);
  EXPECT_LT(a.score, 1.0);
  // The same keypoints given as a file give the same score.
  const fs::path file = fs::temp_directory_path() / "qm3d_graphsim_drawn_keys.txt";
  {
    std::ofstream out(file);
    for (const auto& row : a.details.at("keypoint_rows")) out << row.get<std::size_t>() << "\n";
  }
  const MetricResult c =
      run_metric(registry().get("graphsim"), ref, dist, one, {{"keypoint_file", file.string()}});
  EXPECT_EQ(c.score, a.score);
  fs::remove(file);
  // Another seed draws other keypoints; the default count is round(9048 / 10000) = 1.
  const MetricResult d =
      run_metric(registry().get("graphsim"), ref, dist, one, {{"keypoints", 40}, {"seed", 8}});
  EXPECT_NE(d.details.at("keypoint_rows"), a.details.at("keypoint_rows"));
  EXPECT_EQ(run_metric(registry().get("graphsim"), ref, dist, one, {}).details.at("keypoints"), 1);
}

}  // namespace
}  // namespace qm3d
