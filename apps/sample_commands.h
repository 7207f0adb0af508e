// `qm3d sample` (a mesh's surface as a coloured point cloud) and `qm3d texture-to-vertex` (a
// textured OBJ's texture colours transferred to its vertices).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>


namespace qm3d::app {

/// Sampling options as given on the command line (0 = not given).
struct SamplingCli {
  std::size_t points = 0;
  double density = 0;
  std::uint64_t seed = 1;
};

/// Adds --points, --density (mutually exclusive) and --seed to `cmd`.
void add_sampling_options(CLI::App* cmd, SamplingCli& s, const std::string& default_note);

/// The two subcommands and the values CLI11 parses their options into.
struct SampleCommands {
  CLI::App* sample = nullptr;
  CLI::App* texture_to_vertex = nullptr;
  std::string input, output;
  SamplingCli sampling;
  bool vertices = false;
  std::string mode = "random";        ///< random (area-uniform) or grid (mmetric's)
  int grid_size = 1024;
  std::vector<double> box;            ///< --box: 6 numbers, or empty (the mesh's own box)
  bool normals = false;               ///< --normals: write nx, ny, nz
  bool all_axes = false;
  bool bilinear = false;
  std::string texture;                ///< --texture: a map replacing the mesh's own
};

/// Registers `sample` and `texture-to-vertex`; `add_common` adds --threads, --quiet, ... The
/// result must outlive app.parse().
std::unique_ptr<SampleCommands> add_sample_commands(
    CLI::App& app, const std::function<void(CLI::App*)>& add_common);

/// Runs whichever of the two was parsed and returns its exit code; nullopt when neither was.
std::optional<int> run_sample_commands(const SampleCommands& commands);

}  // namespace qm3d::app
