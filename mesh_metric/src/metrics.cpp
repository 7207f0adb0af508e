#include "qm3d/mesh/metrics.h"

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
  // A textured OBJ takes its vertex colours from its texture (texture.h).
  if (f == MeshFormat::kObj && obj_is_textured(read_file_bytes(path))) {
    MeshFile file = read_textured_obj(path).file;
    return MeshData{std::move(file.mesh), true, std::move(file.warnings)};
  }
  MeshReadOptions o;
  o.require_colors = false;
  o.colour_scale = options.colour_scale;
  MeshFile file = read_mesh(path, f, o);
  const bool colors = !file.mesh.colors.empty();
  return MeshData{std::move(file.mesh), colors, std::move(file.warnings)};
}

ColoredCloud sample(const Input& input, const SurfaceSampling& s) {
  const SamplingOptions o{s.points, s.density, s.seed};
  if (!input.path().empty() && input.format() == FileFormat::kObj) {
    const std::string bytes = read_file_bytes(input.path());
    if (obj_is_textured(bytes)) return sample_surface(parse_textured_obj(bytes, input.path()), o);
  }
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

// mmetric's grid samples of a mesh input: a textured OBJ from its texture (as mmetric with
// --inputMap), else its vertex colours (none: geometry only).
GridSamples grid_sample(const Input& input, const GridSamplingOptions& o) {
  if (!input.is_mesh()) {
    throw FormatError(input.name() + ": a point cloud, not a mesh (grid sampling needs faces)");
  }
  try {
    if (!input.path().empty() && input.format() == FileFormat::kObj) {
      const std::string bytes = read_file_bytes(input.path());
      if (obj_is_textured(bytes)) return sample_grid(parse_textured_obj(bytes, input.path()), o);
    }
    const MeshData& m = input.mesh();
    if (!m.has_colors) {
      ColoredMesh geometry{m.mesh.positions, {}, m.mesh.triangles};
      return sample_grid(geometry, o);
    }
    return sample_grid(m.mesh, o);
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
