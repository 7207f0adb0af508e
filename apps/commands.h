// The metric commands of the qm3d tool: load the inputs, call the libraries, build reports.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "qm3d/mesh/cmdm.h"
#include "qm3d/mesh/msdm2.h"
#include "qm3d/mesh/sampling.h"
#include "qm3d/pointcloud/pcqm.h"
#include "report.h"

namespace qm3d::app {

/// Reads any supported file as a point cloud: PLY / PCD through the cloud reader, OBJ / OFF as
/// the cloud of the mesh's vertices.
ColoredCloud load_cloud(const std::filesystem::path& path);

/// True when the file is a mesh format with faces (OBJ, OFF, or a PLY with a face element).
bool is_mesh_file(const std::filesystem::path& path);

/// CMDM on a pair of mesh files; writes the distortion map when `map` is not empty.
MetricReport run_cmdm(const std::filesystem::path& reference, const std::filesystem::path& distorted,
                      const mesh::CmdmOptions& options, const std::filesystem::path& map = {});

/// MSDM2 on a pair of mesh files (colours optional and ignored); map as for CMDM.
MetricReport run_msdm2(const std::filesystem::path& reference,
                       const std::filesystem::path& distorted, const mesh::Msdm2Options& options,
                       const std::filesystem::path& map = {});

/// PCQM on a pair of cloud (or mesh) files; writes the distortion map when `map` is not empty.
MetricReport run_pcqm(const std::filesystem::path& reference, const std::filesystem::path& distorted,
                      const pointcloud::PcqmOptions& options,
                      const std::filesystem::path& map = {});

/// Samples drawn from each mesh for "pcqm_sampled" when no --points / --density is given.
constexpr std::size_t kDefaultSampledPoints = 20000;

/// Options of every metric, for the commands that run several.
struct MetricOptions {
  mesh::CmdmOptions cmdm;
  mesh::Msdm2Options msdm2;
  pointcloud::PcqmOptions pcqm;
  /// How "pcqm_sampled" samples both meshes (the same options, seed included, for both).
  mesh::SamplingOptions sampling{kDefaultSampledPoints, 0, 1};
};

/// Samples the surface of a mesh file; a textured OBJ is coloured from its texture at each
/// sample's UV, any other mesh from its vertex colours (mesh/sampling.h).
ColoredCloud sample_mesh_file(const std::filesystem::path& path,
                              const mesh::SamplingOptions& options);

/// PCQM on clouds sampled from two mesh files with the same options ("pcqm_sampled").
MetricReport run_pcqm_sampled(const std::filesystem::path& reference,
                              const std::filesystem::path& distorted,
                              const MetricOptions& options);

/// The metrics `compare` runs on the pair: cmdm, msdm2, pcqm (on the vertices) and
/// pcqm_sampled (on sampled clouds) for two meshes; pcqm for anything else.
std::vector<std::string> compare_metrics(const std::filesystem::path& reference,
                                         const std::filesystem::path& distorted);

/// Every metric of compare_metrics, in that order.
std::vector<MetricReport> run_compare(const std::filesystem::path& reference,
                                      const std::filesystem::path& distorted,
                                      const MetricOptions& options);

/// One metric by name ("cmdm", "msdm2", "pcqm", "pcqm_sampled"); FormatError for an unknown
/// name.
MetricReport run_metric(const std::string& metric, const std::filesystem::path& reference,
                        const std::filesystem::path& distorted, const MetricOptions& options);

/// Option values as the tool names them (for --help and the JSON "options" echo).
std::string direction_name(mesh::Direction d);
std::string bbox_mode_name(pointcloud::BboxMode m);

}  // namespace qm3d::app
