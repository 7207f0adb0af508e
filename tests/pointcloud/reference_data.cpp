#include "reference_data.h"

#include <unistd.h>

#include <fstream>
#include <map>
#include <sstream>

#include "qm3d/pointcloud/cloud_io.h"
#include "test_paths.h"

namespace qm3d::pointcloud::test_data {
namespace {

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string item;
  while (std::getline(ss, item, sep)) out.push_back(item);
  return out;
}

// Rows of a reference table; `dir` holds the clouds it names. Lines starting with '#' are
// comments.
std::vector<ReferenceRow> read_rows(const std::filesystem::path& table,
                                    const std::filesystem::path& dir) {
  std::ifstream in(table);
  std::vector<ReferenceRow> rows;
  std::string line;
  // Comment lines, then the header (skipped with them), then the rows.
  while (std::getline(in, line) && !line.empty() && line[0] == '#') continue;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '#') continue;
    const auto c = split(line, ';');
    if (c.size() < 13) continue;
    ReferenceRow r{dir, c[0], c[1], c[2], c[3], {}, std::stod(c[12])};
    for (std::size_t k = 0; k < kNumFeatures; ++k) r.features[k] = std::stod(c[4 + k]);
    rows.push_back(r);
  }
  return rows;
}

// Removes the temp directories made by temp_dir() at exit.
struct TempDirs {
  std::vector<std::filesystem::path> paths;
  ~TempDirs() {
    std::error_code ec;
    for (const auto& p : paths) std::filesystem::remove_all(p, ec);
  }
};

}  // namespace

std::filesystem::path pcqm_dir() { return test::reference_dir() / "pcqm"; }
std::filesystem::path voxel_dir() { return test::reference_dir() / "voxel"; }

const std::vector<ReferenceRow>& reference_rows() {
  static const std::vector<ReferenceRow> rows =
      read_rows(pcqm_dir() / "pcqm_reference.csv", pcqm_dir());
  return rows;
}

const std::vector<ReferenceRow>& voxel_rows() {
  static const std::vector<ReferenceRow> rows =
      read_rows(voxel_dir() / "pcqm_voxel_reference.csv", voxel_dir());
  return rows;
}

const std::vector<ReferenceRow>& voxel_rows_eigen34() {
  static const std::vector<ReferenceRow> rows = read_rows(
      std::filesystem::path(QM3D_TEST_DATA_DIR) / "pcqm_voxel_reference_eigen34.csv", voxel_dir());
  return rows;
}

const ReferenceRow& reference_row(const std::string& name) {
  for (const auto* rows : {&reference_rows(), &voxel_rows()}) {
    for (const auto& r : *rows) {
      if (r.name == name) return r;
    }
  }
  throw std::runtime_error("no row " + name + " in the PCQM reference tables");
}

PcqmOptions options_for(const ReferenceRow& row) {
  PcqmOptions o;
  o.data_dir = test::tables_dir();
  const auto args = split(row.extra_args, ' ');
  for (std::size_t i = 0; i + 1 < args.size(); i += 2) {
    if (args[i] == "-r")
      o.radius_rel = std::stod(args[i + 1]);
    else if (args[i] == "-knn")
      o.knn = std::stoi(args[i + 1]);
    else if (args[i] == "-rx")
      o.radius_factor = std::stod(args[i + 1]);
  }
  return o;
}

const ColoredCloud& cloud(const std::filesystem::path& dir, const std::string& file_name) {
  static std::map<std::filesystem::path, ColoredCloud> cache;
  const std::filesystem::path path = dir / file_name;
  auto it = cache.find(path);
  if (it == cache.end()) it = cache.emplace(path, read_cloud(path)).first;
  return it->second;
}

const ColoredCloud& cloud(const std::string& file_name) { return cloud(pcqm_dir(), file_name); }

const MetricResult& reference_result(const ReferenceRow& row) {
  static std::map<std::string, MetricResult> cache;
  auto it = cache.find(row.name);
  if (it == cache.end()) {
    it = cache
             .emplace(row.name,
                      compute_pcqm(cloud(row.dir, row.reference), cloud(row.dir, row.distorted),
                                   options_for(row)))
             .first;
  }
  return it->second;
}

ColoredCloud head(const ColoredCloud& c, std::size_t n) {
  n = std::min(n, c.size());
  return ColoredCloud{{c.positions.begin(), c.positions.begin() + long(n)},
                      {c.colors.begin(), c.colors.begin() + long(n)}};
}

std::filesystem::path temp_dir(const std::string& tag) {
  static TempDirs dirs;
  static int counter = 0;
  const std::string name =
      "qm3d_pcqm_" + tag + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
  auto dir = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  dirs.paths.push_back(dir);
  return dir;
}

}  // namespace qm3d::pointcloud::test_data
