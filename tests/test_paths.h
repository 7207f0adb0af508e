// Where the tests find their data: the shared reference data beside the project (read at run
// time, never copied) and the LAB2000HL tables.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace qm3d::test {

inline std::filesystem::path shared_data() { return QM3D_SHARED_DATA_DIR; }
inline std::filesystem::path reference_dir() { return shared_data() / "reference"; }
inline std::filesystem::path tables_dir() { return shared_data() / "lab2000hl"; }
inline std::filesystem::path source_dir() { return QM3D_SOURCE_DIR; }

/// Every number of a whitespace-separated text file (a per-vertex dump), in order.
inline std::vector<double> read_column(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::vector<double> v;
  double x;
  while (in >> x) v.push_back(x);
  return v;
}

}  // namespace qm3d::test
