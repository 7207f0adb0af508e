#include "sample_commands.h"

#include <algorithm>
#include <cmath>

#include "commands.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/ply.h"
#include "qm3d/mesh/texture.h"

namespace qm3d::app {
namespace {

constexpr double kMax8Bit = 255.0;

std::uint8_t to_8bit(double c) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(c, 0.0, 1.0) * kMax8Bit));
}

std::vector<std::array<std::uint8_t, 3>> colors_8bit(const std::vector<Rgb>& colors) {
  std::vector<std::array<std::uint8_t, 3>> out(colors.size());
  for (std::size_t i = 0; i < colors.size(); ++i) {
    out[i] = {to_8bit(colors[i].r), to_8bit(colors[i].g), to_8bit(colors[i].b)};
  }
  return out;
}

// Binary PLY with double positions and 8-bit colours (faces when given).
void write_colored_ply(const std::filesystem::path& path, const std::vector<Vec3>& positions,
                       const std::vector<Rgb>& colors, const std::vector<Triangle>& triangles) {
  ply::WriteData data;
  data.positions = positions;
  data.colors = colors_8bit(colors);
  data.triangles = triangles;
  data.double_positions = true;
  ply::write(path, data);
}

ColoredCloud vertex_cloud_of(const std::filesystem::path& path) {
  return vertex_cloud(mesh::read_mesh(path).mesh);
}

int run_sample(const SampleCommands& c) {
  const bool counted = c.sampling.points > 0 || c.sampling.density != 0;
  if (c.vertices == counted) {
    throw std::invalid_argument("sample: give exactly one of --points, --density, --vertices");
  }
  check_outputs({{"MESH", c.input}}, {{"-o", c.output}});
  const ColoredCloud cloud = c.vertices
                                 ? vertex_cloud_of(c.input)
                                 : registry().sampler()(registry().read(c.input),
                                                        {c.sampling.points, c.sampling.density,
                                                         c.sampling.seed});
  write_colored_ply(c.output, cloud.positions, cloud.colors, {});
  return 0;
}

int run_texture_to_vertex(const SampleCommands& c) {
  check_outputs({{"IN", c.input}}, {{"-o", c.output}});
  const mesh::TexturedMesh textured = mesh::read_textured_obj(c.input);
  const ColoredMesh& m = textured.file.mesh;
  write_colored_ply(c.output, m.positions, m.colors, m.triangles);
  return 0;
}

}  // namespace

void add_sampling_options(CLI::App* cmd, SamplingCli& s, const std::string& default_note) {
  auto* points = cmd->add_option("--points", s.points, "Samples per mesh" + default_note)
                     ->check(CLI::PositiveNumber);
  cmd->add_option("--density", s.density,
                  "Samples per unit area (the mesh's units^-2), instead of --points")
      ->check(CLI::PositiveNumber)
      ->excludes(points);
  cmd->add_option("--seed", s.seed, "Seed of the sampling (same seed, same cloud)")
      ->capture_default_str();
}

std::unique_ptr<SampleCommands> add_sample_commands(
    CLI::App& app, const std::function<void(CLI::App*)>& add_common) {
  auto c = std::make_unique<SampleCommands>();
  c->sample = app.add_subcommand(
      "sample",
      "Sample a mesh's surface (area-uniform; colours interpolated, or from the texture "
      "of a textured OBJ) into a coloured point cloud PLY");
  add_common(c->sample);
  c->sample->add_option("MESH", c->input, "Mesh (OBJ, OFF, PLY; textured OBJ)")->required();
  c->sample->add_option("-o,--output", c->output, "Cloud to write (binary PLY, 8-bit colours)")
      ->required()
      ->type_name("CLOUD.ply");
  add_sampling_options(c->sample, c->sampling, "");
  c->sample->add_flag("--vertices", c->vertices, "Write the mesh's vertices instead of samples");
  c->texture_to_vertex =
      app.add_subcommand("texture-to-vertex",
                         "Write a textured OBJ (OBJ + MTL + PNG/JPEG) as a vertex-coloured PLY "
                         "mesh: bilinear texture colour at each vertex's UV, averaged over "
                         "the UVs of seam vertices");
  add_common(c->texture_to_vertex);
  c->texture_to_vertex->add_option("IN", c->input, "Textured OBJ")->required();
  c->texture_to_vertex->add_option("-o,--output", c->output, "Mesh to write (binary PLY)")
      ->required()
      ->type_name("OUT.ply");
  return c;
}

std::optional<int> run_sample_commands(const SampleCommands& commands) {
  if (*commands.sample) return run_sample(commands);
  if (*commands.texture_to_vertex) return run_texture_to_vertex(commands);
  return std::nullopt;
}

}  // namespace qm3d::app
