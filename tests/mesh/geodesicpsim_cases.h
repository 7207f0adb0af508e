// The GeodesicPSIM reference cases (shared/data/reference/geodesicpsim): the table's rows and
// their inputs, gunzipped into a scratch folder of the build tree (never into the data).
#pragma once

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "test_paths.h"

namespace qm3d::test {

inline std::filesystem::path geodesicpsim_dir() { return reference_dir() / "geodesicpsim"; }

/// One CSV row as column -> text.
using CsvRow = std::map<std::string, std::string>;

inline std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream s(line);
  std::string cell;
  while (std::getline(s, cell, ',')) out.push_back(cell);
  return out;
}

/// Rows of a CSV text (first line = header).
inline std::vector<CsvRow> parse_csv(std::istream& in) {
  std::string line;
  std::getline(in, line);
  const auto header = split_csv(line);
  std::vector<CsvRow> rows;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    const auto cells = split_csv(line);
    CsvRow r;
    for (std::size_t i = 0; i < header.size(); ++i) r[header[i]] = i < cells.size() ? cells[i] : "";
    rows.push_back(r);
  }
  return rows;
}

inline std::vector<CsvRow> geodesicpsim_reference_rows() {
  std::ifstream in(geodesicpsim_dir() / "geodesicpsim_reference.csv");
  return parse_csv(in);
}

/// The text of a gzipped file of the data set (gzip -dc).
inline std::string gunzip_text(const std::filesystem::path& gz) {
  std::string out;
  FILE* p = popen(("gzip -dc '" + gz.string() + "'").c_str(), "r");
  if (!p) return out;
  char buf[1 << 16];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  pclose(p);
  return out;
}

/// A scratch folder holding the case inputs: OBJ files gunzipped, MTL and PNG linked.
inline std::filesystem::path geodesicpsim_inputs() {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "qm3d_geodesicpsim_inputs";
  fs::create_directories(dir);
  for (const auto& e : fs::directory_iterator(geodesicpsim_dir() / "inputs")) {
    const fs::path src = e.path();
    const std::string name = src.filename().string();
    if (src.extension() == ".gz") {
      const fs::path dst = dir / src.stem();
      if (!fs::exists(dst) || fs::file_size(dst) == 0) {
        // Test executables may run at once: each writes its own file, then renames it.
        const std::string tmp = (dir / (name + "." + std::to_string(getpid()) + ".tmp")).string();
        std::ofstream(tmp, std::ios::binary) << gunzip_text(src);
        fs::rename(tmp, dst);
      }
    } else if (!fs::exists(dir / name)) {
      std::error_code ec;
      fs::create_symlink(src, dir / name, ec);
    }
  }
  return dir;
}

}  // namespace qm3d::test
