// The pc_error reference table (shared/data/reference/mpeg/pc_error_reference.csv, README there):
// its cases, their pc_error options as qm3d options, and the comparison rule of issue 25: every
// value within 1e-8 relative of the 9 printed digits; "inf" infinite (JSON null); pc_error's zero
// Hausdorff (DBL_MIN, printed 2.22507386e-308) is 0 in qm3d, with an infinite PSNR where pc_error
// prints 10 log10(3 p^2 / DBL_MIN); an empty field (no D2 without normals) is a value qm3d leaves
// out. Header-only, shared by the library and CLI tests (python/tests/test_psnr.py applies the
// same rules).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "test_paths.h"

namespace qm3d::test {

struct PcErrorCase {
  std::string name;
  std::map<std::string, std::string> column;  ///< every column of its row, as printed
  std::vector<std::string> args;              ///< pc_error's options after -a A -b B
};

/// The rows of one of the MPEG tables of shared/data/reference/mpeg/ (`args` = the compare
/// options: pc_error's `args` column, mmetric's `compare_args`).
inline std::vector<PcErrorCase> mpeg_cases(const std::string& table) {
  std::ifstream in(reference_dir() / "mpeg" / table);
  const auto split = [](const std::string& line) {
    std::vector<std::string> f;
    std::stringstream s(line);
    std::string item;
    while (std::getline(s, item, ';')) f.push_back(item);
    if (!line.empty() && line.back() == ';') f.emplace_back();
    return f;
  };
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = split(line);
  std::vector<PcErrorCase> cases;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    const std::vector<std::string> f = split(line);
    PcErrorCase c;
    for (std::size_t i = 0; i < header.size(); ++i) c.column[header[i]] = i < f.size() ? f[i] : "";
    c.name = c.column["case"];
    std::stringstream a(c.column.count("compare_args") ? c.column["compare_args"] : c.column["args"]);
    std::string word;
    while (a >> word) c.args.push_back(word);
    cases.push_back(std::move(c));
  }
  return cases;
}

inline std::vector<PcErrorCase> pc_error_cases() { return mpeg_cases("pc_error_reference.csv"); }

/// mmetric's mesh cases (mm_pcc_reference.csv): sample --mode grid + compare --mode pcc.
inline std::vector<PcErrorCase> mmetric_mesh_cases() { return mpeg_cases("mm_pcc_reference.csv"); }

/// The value of pc_error option `key` ("-r", "-n", "--dropdups", ...), or nullopt.
inline std::optional<std::string> pc_error_option(const PcErrorCase& c, const std::string& key) {
  for (std::size_t i = 0; i < c.args.size(); ++i) {
    if (c.args[i] == key && i + 1 < c.args.size()) return c.args[i + 1];
    if (c.args[i].rfind(key + "=", 0) == 0) return c.args[i].substr(key.size() + 1);
  }
  return std::nullopt;
}

/// The case's options as `qm3d psnr` flags (paths relative to shared/data, as the table's).
inline std::string qm3d_flags(const PcErrorCase& c) {
  std::string flags;
  if (const auto r = pc_error_option(c, "-r")) flags += " --peak " + *r;
  if (const auto n = pc_error_option(c, "-n")) flags += " --normals " + *n;
  if (const auto d = pc_error_option(c, "--dropdups")) flags += " --drop-duplicates " + *d;
  if (const auto p = pc_error_option(c, "--neighborsProc")) flags += " --neighbours " + *p;
  if (const auto a = pc_error_option(c, "--averageNormals")) {
    flags += std::string(" --average-normals=") + (*a == "0" ? "false" : "true");
  }
  if (const auto m = pc_error_option(c, "--mseSpace")) {
    flags += std::string(" --color-space ") + (*m == "0" ? "rgb" : *m == "8" ? "ycocg" : "ycbcr");
  }
  return flags;
}

/// An mmetric mesh case's options as `qm3d psnr` flags on the two meshes.
inline std::string qm3d_mesh_flags(const PcErrorCase& c) {
  std::string flags = " --grid-size " + c.column.at("gridSize");
  if (const auto r = pc_error_option(c, "--resolution"); r && *r != "0") flags += " --peak " + *r;
  if (const auto n = pc_error_option(c, "--normalCalcModificationEnable"); n && *n == "false") {
    flags += " --d2-normals transferred";
  }
  if (const auto d = pc_error_option(c, "--dropDuplicates")) flags += " --drop-duplicates " + *d;
  if (const auto p = pc_error_option(c, "--neighborsProc")) flags += " --neighbours " + *p;
  return flags;
}

/// mmetric's statistics lines ("Mean=", one frame): the symmetric PSNRs clipped at 99.99.
inline void expect_mmetric_statistics(const PcErrorCase& c, const nlohmann::json& features) {
  for (const auto& [column, name] : std::vector<std::pair<std::string, std::string>>{
           {"stat_d1_psnr", "d1_psnr"}, {"stat_d2_psnr", "d2_psnr"}, {"stat_c0_psnr", "c0_psnr"},
           {"stat_c1_psnr", "c1_psnr"}, {"stat_c2_psnr", "c2_psnr"}}) {
    SCOPED_TRACE(c.name + " " + column);
    const double expected = std::stod(c.column.at(column));
    const nlohmann::json& v = features.at(name);
    const double ours = std::min(99.99, v.is_null() ? HUGE_VAL : v.get<double>());
    EXPECT_NEAR(ours, expected, 1e-8 * expected);
  }
}

/// The table's column suffixes and qm3d's value names, in the table's order.
inline const std::vector<std::pair<std::string, std::string>>& pc_error_value_columns() {
  static const std::vector<std::pair<std::string, std::string>> columns = [] {
    std::vector<std::pair<std::string, std::string>> v;
    for (const char* n : {"d1_mse", "d1_psnr", "d2_mse", "d2_psnr", "d1_haus", "d1_haus_psnr",
                          "d2_haus", "d2_haus_psnr", "c0_mse", "c1_mse", "c2_mse", "c0_psnr",
                          "c1_psnr", "c2_psnr", "c0_haus", "c1_haus", "c2_haus", "c0_haus_psnr",
                          "c1_haus_psnr", "c2_haus_psnr"}) {
      std::string ours = n;
      const auto at = ours.find("haus");
      if (at != std::string::npos) ours.replace(at, 4, "hausdorff");
      v.emplace_back(n, ours);
    }
    return v;
  }();
  return columns;
}

constexpr const char* kPcErrorZeroHausdorff = "2.22507386e-308";

/// Checks one value: `printed` is the table's field, `column` its name (e.g. "AB_d1_haus_psnr"),
/// `row` the case's columns (for the zero-Hausdorff rule), `got` qm3d's value (nullopt = left
/// out; +inf for JSON null).
inline void expect_pc_error_value(const PcErrorCase& c, const std::string& column,
                                  std::optional<double> got) {
  const std::string& printed = c.column.at(column);
  SCOPED_TRACE(c.name + " " + column + " (pc_error " + printed + ")");
  if (printed.empty()) {
    EXPECT_FALSE(got.has_value()) << "qm3d gives " << *got;
    return;
  }
  ASSERT_TRUE(got.has_value()) << "qm3d leaves it out";
  const std::string suffix = "_haus_psnr";
  if (column.size() > suffix.size() &&
      column.compare(column.size() - suffix.size(), suffix.size(), suffix) == 0 &&
      c.column.at(column.substr(0, column.size() - 5)) == kPcErrorZeroHausdorff) {
    EXPECT_EQ(*got, HUGE_VAL) << "zero Hausdorff: infinite PSNR";
    return;
  }
  if (printed == kPcErrorZeroHausdorff) {
    EXPECT_EQ(*got, 0.0) << "pc_error's zero Hausdorff (DBL_MIN) is 0";
    return;
  }
  if (printed == "inf") {
    EXPECT_EQ(*got, HUGE_VAL);
    return;
  }
  const double expected = std::stod(printed);
  if (expected == 0) {
    EXPECT_EQ(*got, 0.0);
    return;
  }
  EXPECT_NEAR(*got, expected, 1e-8 * std::fabs(expected));
}

/// A named value of a JSON `features` object: nullopt when absent, +inf for null (an infinite
/// PSNR).
inline std::optional<double> json_feature(const nlohmann::json& features, const std::string& name) {
  if (!features.contains(name)) return std::nullopt;
  const nlohmann::json& v = features.at(name);
  return v.is_null() ? HUGE_VAL : v.get<double>();
}

/// Every value of the case in a psnr result's JSON: both directions and the symmetric values.
inline void expect_pc_error_json(const PcErrorCase& c, const nlohmann::json& j) {
  for (const auto& [column, name] : pc_error_value_columns()) {
    expect_pc_error_value(c, "AB_" + column,
                          json_feature(j["directions"]["ref_to_dist"]["features"], name));
    expect_pc_error_value(c, "BA_" + column,
                          json_feature(j["directions"]["dist_to_ref"]["features"], name));
    expect_pc_error_value(c, "sym_" + column, json_feature(j["features"], name));
  }
}

}  // namespace qm3d::test
