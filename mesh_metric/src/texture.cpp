#include "qm3d/mesh/texture.h"

#include <stb/stb_image.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <system_error>
#include <tuple>

#include "polygon_triangulation.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/ply.h"
#include "text_lines.h"

namespace qm3d::mesh {
namespace {

using detail::Statements;
using detail::Tokens;

constexpr int kRgbChannels = 3;
constexpr double kMax8Bit = 255.0;
constexpr int kMinUvComponents = 2;

[[noreturn]] void fail(const std::string& file, const std::string& what) {
  throw FormatError(file + ": " + what);
}

std::string at_line(std::size_t line) { return "line " + std::to_string(line) + ": "; }

// Colours are kept at float precision like every mesh reader (mesh_io.h); the volatile store
// keeps GCC's vectorizer from dropping the round trip (see mesh_io.cpp).
double to_float_precision(double x) {
  volatile float f = static_cast<float>(x);
  return f;
}

// What an OBJ says about texturing: its UVs, and for every polygon its corners' UVs and material.
struct ObjTexturing {
  std::vector<Uv> uvs;
  std::vector<std::string> mtllibs;
  std::vector<std::uint32_t> corner_uvs;          // all polygons' corners, in order
  std::vector<std::uint32_t> polygon_offsets{0};  // polygon p: [offsets[p], offsets[p+1])
  std::vector<std::string> polygon_materials;     // "" = no usemtl yet
};

// The UV index of a face corner `v/vt[/vn]` (1-based, negative = relative); error when absent.
std::uint32_t corner_uv(std::string_view tok, std::size_t num_uvs, const std::string& file,
                        std::size_t line) {
  const auto slash = tok.find('/');
  const auto end = slash == std::string_view::npos ? slash : tok.find('/', slash + 1);
  const std::string_view uv =
      slash == std::string_view::npos
          ? std::string_view{}
          : tok.substr(slash + 1,
                       end == std::string_view::npos ? std::string_view::npos : end - slash - 1);
  long long i = 0;
  if (uv.empty() || !detail::parse_long(uv, i) || i == 0) {
    fail(file, at_line(line) + "face corner '" + std::string(tok) +
                   "' has no texture coordinate (a textured OBJ needs v/vt on every corner)");
  }
  if (i < 0) i += static_cast<long long>(num_uvs) + 1;
  if (i < 1 || i > static_cast<long long>(num_uvs)) {
    fail(file,
         at_line(line) + "texture coordinate index in '" + std::string(tok) + "' is out of range");
  }
  return static_cast<std::uint32_t>(i - 1);
}

Uv read_uv(Tokens& tokens, const std::string& file, std::size_t line) {
  Uv uv{0, 0};
  std::string_view tok;
  for (int k = 0; k < kMinUvComponents; ++k) {
    if (!tokens.next(tok) || !detail::parse_double(tok, uv[k]) || !std::isfinite(uv[k])) {
      fail(file, at_line(line) + "vt needs two finite numbers u v");
    }
  }
  return uv;
}

ObjTexturing parse_obj_texturing(const std::string& text, const std::string& file) {
  ObjTexturing t;
  std::string current_material;
  Statements lines(text);
  std::string_view keyword, tok;
  Tokens tokens;
  while (lines.next(keyword, tokens)) {
    if (keyword == "vt") {
      t.uvs.push_back(read_uv(tokens, file, lines.line_number()));
    } else if (keyword == "f") {
      while (tokens.next(tok)) {
        t.corner_uvs.push_back(corner_uv(tok, t.uvs.size(), file, lines.line_number()));
      }
      t.polygon_offsets.push_back(static_cast<std::uint32_t>(t.corner_uvs.size()));
      t.polygon_materials.push_back(current_material);
    } else if (keyword == "usemtl") {
      current_material = tokens.next(tok) ? std::string(tok) : "";
    } else if (keyword == "mtllib") {
      while (tokens.next(tok)) t.mtllibs.emplace_back(tok);
    }
  }
  return t;
}

// ---- MTL -------------------------------------------------------------------------------------

struct Material {
  Rgb kd{1, 1, 1};
  std::filesystem::path map_kd;  // empty = none
};

void read_kd(Tokens& tokens, Material& m, const std::string& file, std::size_t line) {
  double v[kRgbChannels];
  std::string_view tok;
  for (double& x : v) {
    if (!tokens.next(tok) || !detail::parse_double(tok, x)) fail(file, at_line(line) + "bad Kd");
  }
  m.kd = {v[0], v[1], v[2]};
}

// Materials by name; `map_Kd`'s last token is the file, relative to the MTL's folder.
std::map<std::string, Material> read_mtl(const std::filesystem::path& path) {
  const std::string text = read_file_bytes(path, kMaxMtlBytes);
  std::map<std::string, Material> materials;
  Material* current = nullptr;
  Statements lines(text);
  std::string_view keyword, tok;
  Tokens tokens;
  while (lines.next(keyword, tokens)) {
    if (keyword == "newmtl") {
      current = &materials[tokens.next(tok) ? std::string(tok) : ""];
    } else if (current && keyword == "Kd") {
      read_kd(tokens, *current, path.string(), lines.line_number());
    } else if (current && keyword == "map_Kd") {
      std::string_view last;
      while (tokens.next(tok)) last = tok;
      if (last.empty()) fail(path.string(), at_line(lines.line_number()) + "map_Kd names no file");
      current->map_kd = path.parent_path() / std::string(last);
    }
  }
  return materials;
}

TextureImage flat_texture(const Rgb& c) { return TextureImage{1, 1, {c}}; }

// Why an OBJ's materials give no usable texture: no mtllib, a material file or texture map that
// is not there, a face without a material, a material no mtllib defines. Empty when they are
// usable. A file that is there but cannot be read (a device, a directory) or decoded is an error,
// found when it is read.
std::string unusable_materials(const ObjTexturing& t, const std::filesystem::path& obj,
                               std::map<std::string, Material>& materials) {
  std::error_code ec;
  if (t.mtllibs.empty()) return "no mtllib: the OBJ names no material file";
  for (const std::string& lib : t.mtllibs) {
    const std::filesystem::path mtl = obj.parent_path() / lib;
    if (!std::filesystem::exists(mtl, ec)) {
      return "its material file " + mtl.string() + " is not there";
    }
    auto read = read_mtl(mtl);
    materials.insert(read.begin(), read.end());
  }
  for (std::size_t p = 0; p < t.polygon_materials.size(); ++p) {
    const std::string& name = t.polygon_materials[p];
    if (name.empty()) return "face " + std::to_string(p) + " has no material (usemtl)";
    const auto m = materials.find(name);
    if (m == materials.end()) return "material '" + name + "' is in no mtllib";
    if (!m->second.map_kd.empty() && !std::filesystem::exists(m->second.map_kd, ec)) {
      return "the texture map " + m->second.map_kd.string() + " of material '" + name +
             "' is not there";
    }
  }
  return {};
}

// One texture per material the faces use, each texture file decoded once however many
// materials name it; returns the texture index of every polygon.
std::vector<std::uint32_t> load_textures(const ObjTexturing& t,
                                         const std::map<std::string, Material>& materials,
                                         std::vector<TextureImage>& textures) {
  std::map<std::string, std::uint32_t> index;
  std::map<std::string, std::uint32_t> decoded;  // texture file -> its texture
  std::vector<std::uint32_t> polygon_texture;
  for (const std::string& name : t.polygon_materials) {
    auto [it, added] = index.emplace(name, static_cast<std::uint32_t>(textures.size()));
    if (added) {
      const Material& m = materials.at(name);
      if (m.map_kd.empty()) {
        textures.push_back(flat_texture(m.kd));
      } else {
        const std::string file = m.map_kd.lexically_normal().string();
        const auto [d, first] = decoded.emplace(file, it->second);
        if (first) textures.push_back(read_texture(m.map_kd));
        it->second = d->second;
      }
    }
    polygon_texture.push_back(it->second);
  }
  return polygon_texture;
}

// Triangulates the corner UVs exactly as read_mesh triangulates the polygons.
void triangulate_uvs(const ObjTexturing& t, const std::vector<std::uint32_t>& polygon_texture,
                     TexturedMesh& out) {
  for (std::size_t p = 0; p + 1 < t.polygon_offsets.size(); ++p) {
    const std::uint32_t begin = t.polygon_offsets[p], end = t.polygon_offsets[p + 1];
    if (end - begin < 3) continue;  // read_mesh refuses such a face
    const std::uint32_t* uv = &t.corner_uvs[begin];
    detail::triangulate_polygon(end - begin,
                                [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
                                  out.triangle_uvs.push_back({uv[a], uv[b], uv[c]});
                                  out.triangle_texture.push_back(polygon_texture[p]);
                                });
  }
}

// Vertex colour = mean of the texture samples at the vertex's distinct (texture, UV) pairs.
std::vector<Rgb> vertex_texture_colors(const TexturedMesh& m) {
  std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>> corners;  // v, tex, uv
  const auto& triangles = m.file.mesh.triangles;
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      corners.emplace_back(triangles[f][k], m.triangle_texture[f], m.triangle_uvs[f][k]);
    }
  }
  std::sort(corners.begin(), corners.end());
  corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
  std::vector<Rgb> sum(m.file.mesh.num_vertices());
  std::vector<int> count(sum.size(), 0);
  for (const auto& [v, tex, uv] : corners) {
    const Rgb c = sample_texture(m.textures[tex], m.uvs[uv]);
    sum[v] = {sum[v].r + c.r, sum[v].g + c.g, sum[v].b + c.b};
    ++count[v];
  }
  for (std::size_t v = 0; v < sum.size(); ++v) {
    const double n = count[v];
    sum[v] = {to_float_precision(sum[v].r / n), to_float_precision(sum[v].g / n),
              to_float_precision(sum[v].b / n)};
  }
  return sum;
}

int wrap(long long i, int n) { return static_cast<int>(((i % n) + n) % n); }

const Rgb& texel(const TextureImage& image, long long x, long long y) {
  return image
      .texels[static_cast<std::size_t>(wrap(y, image.height)) * image.width + wrap(x, image.width)];
}

}  // namespace

TextureImage read_texture(const std::filesystem::path& path) {
  const std::string bytes = read_file_bytes(path, kMaxTextureBytes);
  if (bytes.size() > static_cast<std::size_t>(INT_MAX)) fail(path.string(), "image too large");
  int w = 0, h = 0, channels = 0;
  // The header first: every format (PNG, JPEG, BMP, TGA) under one texel limit before stb
  // allocates the image (a BMP or TGA header can claim any size in a few bytes).
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  if (stbi_info_from_memory(data, static_cast<int>(bytes.size()), &w, &h, &channels) &&
      static_cast<long long>(w) * h > kMaxTextureTexels) {
    fail(path.string(), "texture image of " + std::to_string(w) + " x " + std::to_string(h) +
                            " texels, more than the 16384 x 16384 qm3d reads");
  }
  const std::unique_ptr<unsigned char, void (*)(void*)> pixels(
      stbi_load_from_memory(reinterpret_cast<const unsigned char*>(bytes.data()),
                            static_cast<int>(bytes.size()), &w, &h, &channels, kRgbChannels),
      stbi_image_free);
  if (!pixels) {
    fail(path.string(), std::string("cannot decode the texture image (") + stbi_failure_reason() +
                            "); PNG, JPEG, BMP and TGA are supported");
  }
  TextureImage image{w, h, std::vector<Rgb>(static_cast<std::size_t>(w) * h)};
  for (std::size_t i = 0; i < image.texels.size(); ++i) {
    const unsigned char* p = pixels.get() + kRgbChannels * i;
    image.texels[i] = {p[0] / kMax8Bit, p[1] / kMax8Bit, p[2] / kMax8Bit};
  }
  return image;
}

Rgb sample_texture(const TextureImage& image, const Uv& uv) {
  // Texel centres sit at half-integers of (u W, (1 - v) H).
  const double x = (uv[0] - std::floor(uv[0])) * image.width - 0.5;
  const double y = (1 - (uv[1] - std::floor(uv[1]))) * image.height - 0.5;
  const double x0 = std::floor(x), y0 = std::floor(y);
  const double fx = x - x0, fy = y - y0;
  const auto ix = static_cast<long long>(x0), iy = static_cast<long long>(y0);
  const Rgb &c00 = texel(image, ix, iy), &c10 = texel(image, ix + 1, iy);
  const Rgb &c01 = texel(image, ix, iy + 1), &c11 = texel(image, ix + 1, iy + 1);
  auto mix = [&](double a, double b, double c, double d) {
    return (1 - fy) * ((1 - fx) * a + fx * b) + fy * ((1 - fx) * c + fx * d);
  };
  return {mix(c00.r, c10.r, c01.r, c11.r), mix(c00.g, c10.g, c01.g, c11.g),
          mix(c00.b, c10.b, c01.b, c11.b)};
}

namespace {

// What an OBJ holds that decides whether its colours come from a texture.
struct ObjSurvey {
  bool vertex_colours = false;  // a `v x y z r g b` line
  bool uvs = false;             // a `vt` line
  bool mtllib = false;
};

ObjSurvey survey_obj(const std::string& obj_text) {
  constexpr int kColoredVertexNumbers = 6;
  ObjSurvey s;
  Statements lines(obj_text);
  std::string_view keyword, tok;
  Tokens tokens;
  while (lines.next(keyword, tokens)) {
    if (keyword == "mtllib") s.mtllib = true;
    if (keyword == "vt") s.uvs = true;
    if (keyword != "v" || s.vertex_colours) continue;
    int n = 0;
    while (tokens.next(tok)) ++n;
    s.vertex_colours = n >= kColoredVertexNumbers;
  }
  return s;
}

// The mesh, its corner UVs and its textures (one per polygon in `polygon_texture`).
TexturedMesh assemble(const std::string& text, const std::filesystem::path& path,
                      const ObjTexturing& t, const std::vector<std::uint32_t>& polygon_texture,
                      std::vector<TextureImage> textures) {
  TexturedMesh out;
  out.file = parse_mesh(text, MeshFormat::kObj, path.string(), {/*require_colors=*/false});
  out.textures = std::move(textures);
  triangulate_uvs(t, polygon_texture, out);
  if (out.triangle_uvs.size() != out.file.mesh.triangles.size()) {
    fail(path.string(), "face count mismatch between geometry and texture coordinates");
  }
  out.uvs = t.uvs;
  out.file.mesh.colors = vertex_texture_colors(out);
  return out;
}

// An OBJ's textured mesh, or nothing with the reason in `why` (empty when the OBJ is simply not
// textured). With a texture given (ReadOptions::texture), every face takes its colour from it
// whatever its material. mmetric's rule for several materials is per material index (its
// --inputMapA is a list: map i for the i-th material of the MTL); with one map, its sampler
// (mmImage.h getImage) falls back to the first map for every material, its software renderer
// instead renders a mesh with more materials than maps untextured. qm3d takes one map and
// follows the sampler: the given map for every face, in every metric.
std::optional<TexturedMesh> textured_obj(const std::string& text, const std::filesystem::path& path,
                                         const ReadOptions& options, std::string& why) {
  const ObjSurvey s = survey_obj(text);
  if (!options.texture.empty()) {
    if (!s.uvs) {
      why = options.texture_option + " " + options.texture.string() +
            " given, but the mesh has no texture coordinates (vt): the map is not used";
      return std::nullopt;
    }
    const ObjTexturing t = parse_obj_texturing(text, path.string());
    std::vector<TextureImage> textures{read_texture(options.texture)};
    return assemble(text, path, t, std::vector<std::uint32_t>(t.polygon_materials.size(), 0),
                    std::move(textures));
  }
  if (s.vertex_colours || (!s.mtllib && !s.uvs)) return std::nullopt;
  const ObjTexturing t = parse_obj_texturing(text, path.string());
  std::map<std::string, Material> materials;
  why = unusable_materials(t, path, materials);
  if (!why.empty()) return std::nullopt;
  std::vector<TextureImage> textures;
  const std::vector<std::uint32_t> polygon_texture = load_textures(t, materials, textures);
  return assemble(text, path, t, polygon_texture, std::move(textures));
}

// ---- PLY -------------------------------------------------------------------------------------

// Texture coordinates per vertex (both names of a pair) or per corner (face list `texcoord`).
bool ply_header_has_uvs(const ply::Header& h) {
  for (const ply::Element& e : h.elements) {
    const auto has = [&e](const char* name, bool list) {
      return std::any_of(e.properties.begin(), e.properties.end(), [&](const ply::Property& p) {
        return p.name == name && p.is_list == list;
      });
    };
    if (e.name == "face" && has("texcoord", true)) return true;
    if (e.name != "vertex") continue;
    if ((has("texture_u", false) && has("texture_v", false)) ||
        (has("s", false) && has("t", false)) || (has("u", false) && has("v", false))) {
      return true;
    }
  }
  return false;
}

// A PLY's texture maps: the given one, else its `comment TextureFile` lines (relative to its
// folder); empty with `why` set when one is not there.
std::vector<std::filesystem::path> ply_maps(const ply::Content& c,
                                            const std::filesystem::path& path,
                                            const ReadOptions& options, std::string& why) {
  if (!options.texture.empty()) return {options.texture};
  std::vector<std::filesystem::path> maps;
  std::error_code ec;
  for (const std::string& name : c.texture_files) {
    maps.push_back(path.parent_path() / name);
    if (!std::filesystem::exists(maps.back(), ec)) {
      why = "its texture map " + maps.back().string() + " (comment TextureFile) is not there";
      return {};
    }
  }
  if (maps.empty()) why = "it has texture coordinates but no `comment TextureFile` line";
  return maps;
}

// Per-corner UVs (face `texcoord` lists) as ObjTexturing's corner list, or per-vertex UVs
// (texture_u / texture_v, s / t, u / v) through the file's vertex numbers.
void ply_uvs(const ply::Content& c, TexturedMesh& out) {
  if (c.face_texcoords.empty()) {
    out.uvs.assign(c.uvs.begin(), c.uvs.end());
    for (const Triangle& t : out.file.mesh.triangles) {
      out.triangle_uvs.push_back(
          {out.file.file_vertex[t[0]], out.file.file_vertex[t[1]], out.file.file_vertex[t[2]]});
    }
    return;
  }
  for (std::size_t k = 0; k + 1 < c.face_texcoords.size(); k += 2) {
    out.uvs.push_back({c.face_texcoords[k], c.face_texcoords[k + 1]});
  }
  for (std::size_t f = 0; f + 1 < c.face_offsets.size(); ++f) {
    const std::uint32_t begin = c.face_offsets[f];
    detail::triangulate_polygon(c.face_offsets[f + 1] - begin,
                                [&](std::uint32_t a, std::uint32_t b, std::uint32_t d) {
                                  out.triangle_uvs.push_back({begin + a, begin + b, begin + d});
                                });
  }
}

// Each triangle's texture: its face's `texnumber` (0 without one), as the polygons are
// triangulated; `why` set when a number names no map.
bool ply_triangle_textures(const ply::Content& c, std::size_t maps, TexturedMesh& out,
                           std::string& why) {
  for (std::size_t f = 0; f + 1 < c.face_offsets.size(); ++f) {
    const std::int64_t n = c.face_texnumbers.empty() ? 0 : c.face_texnumbers[f];
    if (n < 0 || static_cast<std::size_t>(n) >= maps) {
      why = "face " + std::to_string(f) + " has texnumber " + std::to_string(n) + " but " +
            std::to_string(maps) + " texture map(s)";
      return false;
    }
    detail::triangulate_polygon(c.face_offsets[f + 1] - c.face_offsets[f],
                                [&](std::uint32_t, std::uint32_t, std::uint32_t) {
                                  out.triangle_texture.push_back(static_cast<std::uint32_t>(n));
                                });
  }
  return true;
}

// A PLY mesh with texture coordinates (per vertex or per corner) takes its colours from its
// `comment TextureFile` maps (or the given one), whatever vertex colours it also has. One map
// per `texnumber` (MeshLab's multi-texture PLY), map 0 for a face without one; with a map given,
// every face takes it (the rule of textured_obj).
std::optional<TexturedMesh> textured_ply(const std::string& bytes,
                                         const std::filesystem::path& path,
                                         const ReadOptions& options, std::string& why) {
  if (!ply_header_has_uvs(ply::parse_header(bytes, path.string()))) {
    if (!options.texture.empty()) {
      why = options.texture_option + " " + options.texture.string() +
            " given, but the mesh has no texture coordinates: the map is not used";
    }
    return std::nullopt;
  }
  const ply::Content c = ply::parse(bytes, path.string());
  if (c.uvs.empty() && c.face_texcoords.empty()) {
    if (!options.texture.empty()) {
      why = options.texture_option + " " + options.texture.string() +
            " given, but the mesh has no texture coordinates: the map is not used";
    }
    return std::nullopt;
  }
  const std::vector<std::filesystem::path> maps = ply_maps(c, path, options, why);
  if (maps.empty()) return std::nullopt;
  TexturedMesh out;
  out.file = parse_mesh(bytes, MeshFormat::kPly, path.string(), {/*require_colors=*/false});
  ply_uvs(c, out);
  const ply::Content* numbers = &c;
  ply::Content given;  // a given map: every face takes it
  if (!options.texture.empty()) {
    given.face_offsets = c.face_offsets;
    numbers = &given;
  }
  if (!ply_triangle_textures(*numbers, maps.size(), out, why)) return std::nullopt;
  for (const auto& map : maps) out.textures.push_back(read_texture(map));
  out.file.mesh.colors = vertex_texture_colors(out);
  return out;
}

}  // namespace

bool obj_is_textured(const std::string& obj_text) {
  const ObjSurvey s = survey_obj(obj_text);
  return s.mtllib && !s.vertex_colours;
}

TexturedMesh read_textured_obj(const std::filesystem::path& path) {
  return parse_textured_obj(read_file_bytes(path), path);
}

TexturedMesh parse_textured_obj(const std::string& text, const std::filesystem::path& path) {
  std::string why;
  std::optional<TexturedMesh> m = textured_obj(text, path, {}, why);
  if (!m) fail(path.string(), why.empty() ? "not a textured OBJ (no mtllib)" : why);
  return std::move(*m);
}

bool may_be_textured(const std::filesystem::path& path, MeshFormat format,
                     const ReadOptions& options) {
  if (format == MeshFormat::kOff) return false;
  if (format == MeshFormat::kObj || !options.texture.empty()) return true;
  constexpr std::size_t kHeadBytes = 1 << 20;  // ply.cpp's kMaxHeaderBytes
  std::ifstream in(path, std::ios::binary);
  std::string head(kHeadBytes, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  try {
    return ply_header_has_uvs(ply::parse_header(head, path.string(), std::uintmax_t(-1)));
  } catch (const FormatError&) {
    return true;  // the full read says what is wrong
  }
}

std::optional<TexturedMesh> read_textured_mesh(const std::string& bytes, MeshFormat format,
                                               const std::filesystem::path& path,
                                               const ReadOptions& options,
                                               std::vector<std::string>* warnings) {
  std::string why;
  std::optional<TexturedMesh> m;
  if (format == MeshFormat::kObj) m = textured_obj(bytes, path, options, why);
  if (format == MeshFormat::kPly) m = textured_ply(bytes, path, options, why);
  if (!m && !why.empty() && warnings) {
    warnings->push_back(path.string() + ": " + why + "; " + kReadWithoutTexture +
                        (options.texture.empty()
                             ? " (give its map with " + options.texture_option + ")"
                             : std::string()));
  }
  return m;
}

std::filesystem::path obj_texture_file(const std::string& text, const std::filesystem::path& path) {
  const ObjTexturing t = parse_obj_texturing(text, path.string());
  if (t.mtllibs.empty())
    fail(path.string(), "no mtllib: the OBJ names no material file (untextured)");
  std::map<std::string, Material> materials;
  const std::string why = unusable_materials(t, path, materials);
  if (!why.empty()) fail(path.string(), why);
  std::filesystem::path file;
  for (const std::string& name : t.polygon_materials) {
    const Material& m = materials.at(name);  // unusable_materials checked that it is defined
    if (m.map_kd.empty()) fail(path.string(), "material '" + name + "' has no texture image (map_Kd)");
    if (!file.empty() && file != m.map_kd) {
      fail(path.string(), "its materials name several texture images (one is supported)");
    }
    file = m.map_kd;
  }
  if (file.empty()) fail(path.string(), "no faces");
  return file;
}

}  // namespace qm3d::mesh
