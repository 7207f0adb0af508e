// The PointSSIM reference table (../shared/data/reference/pointssim/pointssim_reference.csv):
// one row per (case, K) with 252 values named <attr>_<ESTIMATOR>_<Pooling>_<BA|AB|Sym>, and the
// acceptance rule of issue 41. Shared by the library test and the tool's test.
#pragma once

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "test_paths.h"

namespace qm3d::test {

inline std::filesystem::path pointssim_dir() { return reference_dir() / "pointssim"; }

struct PointssimRow {
  std::map<std::string, std::string> fields;  ///< every column by name
  std::string field(const std::string& name) const { return fields.at(name); }
  /// The voxel crops: their normal and curvature columns depend on the solver where the
  /// neighbourhoods are degenerate (the data set's README), so only geometry and colour count.
  bool voxel() const { return field("fileA").rfind("vox", 0) == 0; }
};

inline std::vector<PointssimRow> pointssim_rows() {
  std::ifstream in(pointssim_dir() / "pointssim_reference.csv");
  std::vector<std::string> header;
  std::vector<PointssimRow> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream s(line);
    std::string cell;
    while (std::getline(s, cell, ',')) cells.push_back(cell);
    if (header.empty()) {
      header = cells;
      continue;
    }
    PointssimRow row;
    for (std::size_t k = 0; k < cells.size() && k < header.size(); ++k) {
      row.fields[header[k]] = cells[k];
    }
    rows.push_back(row);
  }
  return rows;
}

/// One reference value: its name in qm3d ("geom_std_mean") and its direction ("BA", "AB",
/// "Sym").
struct PointssimColumn {
  std::string column, attribute, name, direction;
};

inline std::vector<PointssimColumn> pointssim_columns(const PointssimRow& row) {
  std::vector<PointssimColumn> out;
  for (const auto& [column, value] : row.fields) {
    std::vector<std::string> parts;
    std::stringstream s(column);
    std::string part;
    while (std::getline(s, part, '_')) parts.push_back(part);
    if (parts.size() != 4) continue;
    if (parts[0] != "geom" && parts[0] != "norm" && parts[0] != "curv" && parts[0] != "color") {
      continue;
    }
    std::string name = parts[0] + "_" + parts[1] + "_" + parts[2];
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    out.push_back({column, parts[0], name, parts[3]});
  }
  return out;
}

/// Whether a column is checked for this row (every column of the float clouds; geometry and
/// colour of the voxel crops).
inline bool pointssim_checked(const PointssimRow& row, const PointssimColumn& c) {
  return !row.voxel() || c.attribute == "geom" || c.attribute == "color";
}

/// Issue 41's tolerance: 1e-10 relative, or 1e-13 absolute.
inline bool pointssim_agrees(double got, double expected) {
  const double diff = std::abs(got - expected);
  return diff <= 1e-13 || diff <= 1e-10 * std::abs(expected);
}

}  // namespace qm3d::test
