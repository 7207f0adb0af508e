#include "qm3d/mesh/metrics.h"

#include <optional>

#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/mesh/geodesicpsim.h"
#include "qm3d/mesh/grid_sampling.h"
#include "qm3d/mesh/mesh_io.h"
#include "qm3d/mesh/sampling.h"
#include "qm3d/mesh/texture.h"

namespace qm3d::mesh {
namespace {

MeshFormat mesh_format(FileFormat f, const std::filesystem::path& path) {
  switch (f) {
    case FileFormat::kObj: return MeshFormat::kObj;
    case FileFormat::kOff: return MeshFormat::kOff;
    case FileFormat::kPly: return MeshFormat::kPly;
    case FileFormat::kPcd: break;
  }
  throw FormatError(path.string() + ": a PCD file holds a point cloud, not a mesh");
}

MeshData read_mesh_data(const std::filesystem::path& path, FileFormat format,
                        const ReadOptions& options) {
  const MeshFormat f = mesh_format(format, path);
  // A textured mesh takes its vertex colours from its texture (texture.h).
  std::vector<std::string> no_texture;
  if (may_be_textured(path, f, options)) {
    if (auto textured = read_textured_mesh(read_file_bytes(path), f, path, options, &no_texture)) {
      return MeshData{std::move(textured->file.mesh), true, std::move(textured->file.warnings)};
    }
  }
  MeshReadOptions o;
  o.require_colors = false;
  o.colour_scale = options.colour_scale;
  MeshFile file = read_mesh(path, f, o);
  const bool colors = !file.mesh.colors.empty();
  file.warnings.insert(file.warnings.end(), no_texture.begin(), no_texture.end());
  return MeshData{std::move(file.mesh), colors, std::move(file.warnings)};
}

// The textured mesh of a mesh input's file (texture.h), or nothing (then its MeshData, whose
// warnings say why a mesh with texture coordinates is read without its texture).
std::optional<TexturedMesh> textured_input(const Input& input) {
  if (input.path().empty() || !input.is_mesh()) return std::nullopt;
  const MeshFormat f = mesh_format(input.format(), input.path());
  if (!may_be_textured(input.path(), f, input.read_options())) return std::nullopt;
  return read_textured_mesh(read_file_bytes(input.path()), f, input.path(), input.read_options());
}

ColoredCloud sample(const Input& input, const SurfaceSampling& s) {
  const SamplingOptions o{s.points, s.density, s.seed};
  if (auto textured = textured_input(input)) return sample_surface(*textured, o);
  const MeshData& m = input.mesh();
  if (!m.has_colors) {
    throw FormatError(input.name() + ": no vertex colours (sampling needs a colour per vertex)");
  }
  try {
    return sample_surface(m.mesh, o);
  } catch (const NumericError& e) {
    throw NumericError(input.name() + ": " + e.what());
  }
}

// A mesh reader's warnings about a texture it could not use, without the file name (the caller
// names the input).
void add_texture_warnings(const Input& input, GridSamples& samples) {
  const std::string prefix = input.path().string() + ": ";
  for (const std::string& w : input.mesh().warnings) {
    if (w.find(kReadWithoutTexture) == std::string::npos) continue;
    samples.warnings.push_back(w.compare(0, prefix.size(), prefix) == 0 ? w.substr(prefix.size())
                                                                        : w);
  }
}

// mmetric's grid samples of a mesh input: a textured mesh from its texture (as mmetric with
// --inputMap), else its vertex colours (none: geometry only).
GridSamples grid_sample(const Input& input, const GridSamplingOptions& o) {
  if (!input.is_mesh()) {
    throw FormatError(input.name() + ": a point cloud, not a mesh (grid sampling needs faces)");
  }
  try {
    if (auto textured = textured_input(input)) return sample_grid(*textured, o);
    const MeshData& m = input.mesh();
    GridSamples samples = m.has_colors
                              ? sample_grid(m.mesh, o)
                              : sample_grid(ColoredMesh{m.mesh.positions, {}, m.mesh.triangles}, o);
    add_texture_warnings(input, samples);
    return samples;
  } catch (const NumericError& e) {
    throw NumericError(input.name() + ": " + e.what());
  }
}

}  // namespace

void register_metrics(Registry& registry) {
  registry.readers().mesh = read_mesh_data;
  registry.readers().mesh_vertices = [](const std::filesystem::path& path, FileFormat format,
                                        const ReadOptions& options) {
    return read_mesh_vertices_data(path, mesh_format(format, path), options);
  };
  registry.set_sampler(sample);
  registry.set_grid_sampler(grid_sample);
  registry.set_colour_matcher(match_surface_colours);
  registry.add(cmdm_spec());
  registry.add(msdm2_spec());
  registry.add(geodesicpsim_spec());
}

}  // namespace qm3d::mesh
