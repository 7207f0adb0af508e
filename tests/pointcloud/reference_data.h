// The PCQM reference data (../shared/data/reference/pcqm), read once per test run and shared.
#pragma once

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "qm3d/common/features.h"
#include "qm3d/common/types.h"
#include "qm3d/pointcloud/pcqm.h"

namespace qm3d::pointcloud::test_data {

/// One row of pcqm/pcqm_reference.csv or voxel/pcqm_voxel_reference.csv.
struct ReferenceRow {
  std::filesystem::path dir;  ///< the directory of the table and its clouds
  std::string name;        ///< e.g. "def_sphere_50k_gnoise0.001"
  std::string reference;   ///< argv1 file name
  std::string distorted;   ///< argv2 file name
  std::string extra_args;  ///< "" or "-r 0.02"
  FeatureVector features{};
  double pcqm = 0;
};

/// gtest prints a row by its name.
inline void PrintTo(const ReferenceRow& row, std::ostream* out) { *out << row.name; }

std::filesystem::path pcqm_dir();
std::filesystem::path voxel_dir();

/// All rows of pcqm/pcqm_reference.csv (empty when the file is missing: the tests then fail).
const std::vector<ReferenceRow>& reference_rows();
/// All rows of voxel/pcqm_voxel_reference.csv (voxelised clouds: ties everywhere).
const std::vector<ReferenceRow>& voxel_rows();
/// The same cases scored by the reference rebuilt with Debian's Eigen 3.4
/// (tests/data/pcqm_voxel_reference_eigen34.csv, provenance in its header).
const std::vector<ReferenceRow>& voxel_rows_eigen34();
/// A row of either table by name.
const ReferenceRow& reference_row(const std::string& name);

/// The options reproducing a row's command line.
PcqmOptions options_for(const ReferenceRow& row);

/// A cloud of the pcqm reference directory (or of `dir`), read once.
const ColoredCloud& cloud(const std::string& file_name);
const ColoredCloud& cloud(const std::filesystem::path& dir, const std::string& file_name);

/// compute_pcqm of a row with its options, computed once per run.
const MetricResult& reference_result(const ReferenceRow& row);

/// The first n points of a cloud.
ColoredCloud head(const ColoredCloud& c, std::size_t n);

/// A fresh empty directory under the system temp directory, removed at exit.
std::filesystem::path temp_dir(const std::string& tag);

}  // namespace qm3d::pointcloud::test_data
