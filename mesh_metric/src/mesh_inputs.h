// The meshes of a registry run (qm3d/common/metric.h), for the mesh metrics' specs. Internal.
#pragma once

#include <string>

#include "qm3d/common/error.h"
#include "qm3d/common/metric.h"

namespace qm3d::mesh::detail {

/// The input's mesh; FormatError naming it when `colors` are required and it has none.
inline const ColoredMesh& input_mesh(const Input& input, bool colors, const std::string& metric) {
  const MeshData& m = input.mesh();
  if (colors && !m.has_colors) {
    throw FormatError(input.name() + ": no vertex colours (" + metric +
                      " needs a colour per vertex)");
  }
  return m.mesh;
}

/// The readers' repairs of both meshes (taken before the metric runs: it may free its inputs).
inline std::vector<std::string> reader_warnings(const Input& reference, const Input& distorted) {
  std::vector<std::string> all = reference.mesh().warnings;
  const auto& d = distorted.mesh().warnings;
  all.insert(all.end(), d.begin(), d.end());
  return all;
}

/// `first` (the readers' repairs) before the metric's own warnings.
inline void prepend_warnings(MetricResult& r, std::vector<std::string> first) {
  first.insert(first.end(), r.warnings.begin(), r.warnings.end());
  r.warnings = std::move(first);
}

/// The run options as a metric's options type (CmdmOptions, Msdm2Options).
template <typename Options>
Options with_run_options(const RunOptions& run) {
  Options o;
  static_cast<RunOptions&>(o) = run;
  return o;
}

}  // namespace qm3d::mesh::detail
