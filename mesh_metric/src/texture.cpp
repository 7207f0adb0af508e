#include "qm3d/mesh/texture.h"

#include <stb/stb_image.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <map>
#include <memory>
#include <tuple>

#include "polygon_triangulation.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
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

std::map<std::string, Material> read_materials(const ObjTexturing& t,
                                               const std::filesystem::path& obj) {
  std::map<std::string, Material> all;
  for (const std::string& lib : t.mtllibs) {
    auto materials = read_mtl(obj.parent_path() / lib);
    all.insert(materials.begin(), materials.end());
  }
  return all;
}

TextureImage flat_texture(const Rgb& c) { return TextureImage{1, 1, {c}}; }

// One texture per material the faces use, each texture file decoded once however many
// materials name it; returns the texture index of every polygon.
std::vector<std::uint32_t> load_textures(const ObjTexturing& t, const std::filesystem::path& obj,
                                         std::vector<TextureImage>& textures) {
  const auto materials = read_materials(t, obj);
  std::map<std::string, std::uint32_t> index;
  std::map<std::string, std::uint32_t> decoded;  // texture file -> its texture
  std::vector<std::uint32_t> polygon_texture;
  for (std::size_t p = 0; p < t.polygon_materials.size(); ++p) {
    const std::string& name = t.polygon_materials[p];
    if (name.empty()) fail(obj.string(), "face " + std::to_string(p) + " has no material (usemtl)");
    auto [it, added] = index.emplace(name, static_cast<std::uint32_t>(textures.size()));
    if (added) {
      const auto m = materials.find(name);
      if (m == materials.end()) fail(obj.string(), "material '" + name + "' is in no mtllib");
      if (m->second.map_kd.empty()) {
        textures.push_back(flat_texture(m->second.kd));
      } else {
        const std::string file = m->second.map_kd.lexically_normal().string();
        const auto [d, first] = decoded.emplace(file, it->second);
        if (first) textures.push_back(read_texture(m->second.map_kd));
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
  const std::unique_ptr<unsigned char, void (*)(void*)> pixels(
      stbi_load_from_memory(reinterpret_cast<const unsigned char*>(bytes.data()),
                            static_cast<int>(bytes.size()), &w, &h, &channels, kRgbChannels),
      stbi_image_free);
  if (!pixels) {
    fail(path.string(), std::string("cannot decode the texture image (") + stbi_failure_reason() +
                            "); PNG and JPEG are supported");
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

bool obj_is_textured(const std::string& obj_text) {
  constexpr int kColoredVertexNumbers = 6;
  bool mtllib = false;
  Statements lines(obj_text);
  std::string_view keyword, tok;
  Tokens tokens;
  while (lines.next(keyword, tokens)) {
    if (keyword == "mtllib") mtllib = true;
    if (keyword != "v") continue;
    int n = 0;
    while (tokens.next(tok)) ++n;
    if (n >= kColoredVertexNumbers) return false;
  }
  return mtllib;
}

TexturedMesh read_textured_obj(const std::filesystem::path& path) {
  return parse_textured_obj(read_file_bytes(path), path);
}

TexturedMesh parse_textured_obj(const std::string& text, const std::filesystem::path& path) {
  TexturedMesh out;
  out.file = parse_mesh(text, MeshFormat::kObj, path.string(), {/*require_colors=*/false});
  const ObjTexturing t = parse_obj_texturing(text, path.string());
  if (t.mtllibs.empty()) fail(path.string(), "no mtllib: the OBJ names no material file");
  const std::vector<std::uint32_t> polygon_texture = load_textures(t, path, out.textures);
  triangulate_uvs(t, polygon_texture, out);
  if (out.triangle_uvs.size() != out.file.mesh.triangles.size()) {
    fail(path.string(), "face count mismatch between geometry and texture coordinates");
  }
  out.uvs = t.uvs;
  out.file.mesh.colors = vertex_texture_colors(out);
  return out;
}

}  // namespace qm3d::mesh
