#include "sample_commands.h"

#include <algorithm>
#include <cmath>
#include <iostream>

#include "qm3d/scoring/score.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/grid_samples.h"
#include "qm3d/common/ply.h"
#include "qm3d/mesh/texture.h"

namespace qm3d::app {
using namespace qm3d::scoring;  // NOLINT: the scoring this command drives
namespace {

constexpr double kMax8Bit = 255.0;

void warn(const std::string& w) { std::cerr << "qm3d: warning: " << w << "\n"; }

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

// The texture map of --texture, named as such in the warning about a mesh without a usable one.
ReadOptions texture_read_options(const SampleCommands& c) {
  ReadOptions o;
  o.texture = c.texture;
  o.texture_option = "--texture";
  return o;
}

ColoredCloud vertex_cloud_of(const std::filesystem::path& path) {
  return vertex_cloud(mesh::read_mesh(path).mesh);
}

// mmetric's grid samples (mm sample --mode grid --useNormal): float32 positions (and normals with
// --normals), 8-bit colours, as mmetric writes them.
int run_grid_sample(const SampleCommands& c) {
  if (c.vertices || c.sampling.points > 0 || c.sampling.density != 0) {
    throw std::invalid_argument("sample --mode grid: --points, --density and --vertices apply "
                                "to --mode random");
  }
  check_outputs({{"MESH", c.input}, {"--texture", c.texture}}, {{"-o", c.output}});
  GridSamplingOptions o;
  o.grid_size = c.grid_size;
  o.all_axes = c.all_axes;
  o.bilinear = c.bilinear;
  if (!c.box.empty()) {
    FloatBox b;
    for (int k = 0; k < 3; ++k) {
      b.min[k] = static_cast<float>(c.box[k]);
      b.max[k] = static_cast<float>(c.box[3 + k]);
    }
    o.box = b;
  }
  const Input input = default_registry().read(c.input, texture_read_options(c));
  if (!input.is_mesh()) throw FormatError(c.input + ": a point cloud, not a mesh (no faces to sample)");
  const GridSamples s = default_registry().grid_sampler()(input, o);
  for (const std::string& w : s.warnings) warn(c.input + ": " + w);
  if (s.colours.empty()) warn(c.input + ": no vertex colours: the cloud has none");
  ply::WriteData data;
  data.positions.resize(s.positions.size());
  for (std::size_t i = 0; i < s.positions.size(); ++i) {
    data.positions[i] = {s.positions[i][0], s.positions[i][1], s.positions[i][2]};
  }
  data.colors = s.colours;
  if (c.normals) {
    for (int k = 0; k < 3; ++k) {
      std::vector<float> v(s.normals.size());
      for (std::size_t i = 0; i < v.size(); ++i) v[i] = s.normals[i][k];
      data.extra_scalars.emplace_back(std::string("n") + "xyz"[k], std::move(v));
    }
  }
  ply::write(c.output, data);
  return 0;
}

int run_sample(const SampleCommands& c) {
  if (c.mode == "grid") return run_grid_sample(c);
  const bool counted = c.sampling.points > 0 || c.sampling.density != 0;
  if (c.vertices == counted) {
    throw std::invalid_argument("sample: give exactly one of --points, --density, --vertices");
  }
  check_outputs({{"MESH", c.input}, {"--texture", c.texture}}, {{"-o", c.output}});
  const ColoredCloud cloud = c.vertices
                                 ? vertex_cloud_of(c.input)
                                 : default_registry().sampler()(default_registry().read(c.input, texture_read_options(c)),
                                                        {c.sampling.points, c.sampling.density,
                                                         c.sampling.seed});
  write_colored_ply(c.output, cloud.positions, cloud.colors, {});
  return 0;
}

int run_texture_to_vertex(const SampleCommands& c) {
  check_outputs({{"IN", c.input}, {"--texture", c.texture}}, {{"-o", c.output}});
  const std::filesystem::path path = c.input;
  const FileFormat file_format = detect_format(path);
  if (file_format == FileFormat::kPcd) throw FormatError(c.input + ": a point cloud, not a mesh");
  const mesh::MeshFormat format = file_format == FileFormat::kObj   ? mesh::MeshFormat::kObj
                                  : file_format == FileFormat::kOff ? mesh::MeshFormat::kOff
                                                                    : mesh::MeshFormat::kPly;
  std::vector<std::string> no_texture;
  const auto textured = mesh::read_textured_mesh(read_file_bytes(path), format, path,
                                                 texture_read_options(c), &no_texture);
  if (!textured) {
    throw FormatError(no_texture.empty()
                          ? c.input + ": not a textured mesh (no texture coordinates, or an OBJ "
                                      "with vertex colours)"
                          : no_texture.front());
  }
  const ColoredMesh& m = textured->file.mesh;
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
  c->sample->add_option("--mode", c->mode,
                        "random: area-uniform random samples (--points / --density); grid: MPEG "
                        "mmetric's grid sampling (mm sample --mode grid --useNormal), the samples "
                        "V-DMC's PSNR compares")
      ->check(CLI::IsMember({"random", "grid"}))
      ->capture_default_str();
  c->sample->add_option("--grid-size", c->grid_size,
                        "Grid mode: nodes along the box's longest side (mmetric --gridSize)")
      ->check(CLI::Range(2, 1000000))
      ->capture_default_str();
  c->sample->add_option("--box", c->box,
                        "Grid mode: the grid's box MINX MINY MINZ MAXX MAXY MAXZ (mmetric "
                        "--minPos/--maxPos; default: the mesh's own vertex box)")
      ->expected(6);
  c->sample->add_flag("--normals", c->normals,
                      "Grid mode: also write each sample's face normal (nx, ny, nz)");
  c->sample->add_flag("--all-axes", c->all_axes,
                      "Grid mode: rays along all three axes (mmetric without --useNormal)");
  c->sample->add_flag("--bilinear", c->bilinear,
                      "Grid mode: bilinear texture lookups for textured OBJ (mmetric --bilinear)");
  const char* texture_help =
      "Texture map (PNG, JPEG, BMP, TGA) replacing the mesh's own: every face with texture "
      "coordinates takes its colour from it (mmetric's --inputMap)";
  c->sample->add_option("--texture", c->texture, texture_help)->type_name("FILE");
  c->texture_to_vertex =
      app.add_subcommand("texture-to-vertex",
                         "Write a textured mesh (OBJ + MTL + map, or PLY with TextureFile) as a vertex-coloured PLY "
                         "mesh: bilinear texture colour at each vertex's UV, averaged over "
                         "the UVs of seam vertices");
  add_common(c->texture_to_vertex);
  c->texture_to_vertex->add_option("IN", c->input, "Textured OBJ or PLY")->required();
  c->texture_to_vertex->add_option("--texture", c->texture, texture_help)->type_name("FILE");
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
