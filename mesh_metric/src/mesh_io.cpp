#include "qm3d/mesh/mesh_io.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "halfedge_mesh.h"
#include "polygon_triangulation.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/ply.h"
#include "qm3d/common/reading.h"
#include "qm3d/mesh/texture.h"
#include "text_lines.h"

namespace qm3d::mesh {
namespace {

using detail::check_finite;
using detail::LineReader;
using detail::Statements;
using detail::Tokens;

// What a reader extracts before validation: positions, raw colour values (per vertex, maybe
// missing) and polygons in compressed form.
struct RawMesh {
  std::vector<Vec3> positions;
  std::vector<std::optional<Rgb>> colors;
  bool colors_are_unit_range = false;  // PLY: already normalised from the type's range
  std::vector<std::string> warnings;   // the PLY reader's
  std::vector<std::uint32_t> face_offsets{0};
  std::vector<std::uint32_t> face_indices;
};

[[noreturn]] void fail(const std::string& file, const std::string& what) {
  throw FormatError(file + ": " + what);
}

// Reads n numbers from the tokens; false if fewer are present; error if one is not a number.
bool read_numbers(Tokens& tokens, double* out, int n, const std::string& file, std::size_t line) {
  std::string_view tok;
  for (int i = 0; i < n; ++i) {
    if (!tokens.next(tok)) return false;
    if (!detail::parse_double(tok, out[i])) {
      fail(file, "line " + std::to_string(line) + ": '" + std::string(tok) + "' is not a number");
    }
  }
  return true;
}

// ---- OBJ -------------------------------------------------------------------------------------

std::uint32_t obj_index(std::string_view tok, std::size_t num_vertices, const std::string& file,
                        std::size_t line) {
  const auto slash = tok.find('/');
  long long i = 0;
  if (!detail::parse_long(tok.substr(0, slash), i) || i == 0) {
    fail(file, "line " + std::to_string(line) + ": bad face index '" + std::string(tok) + "'");
  }
  if (i < 0) i += static_cast<long long>(num_vertices) + 1;  // relative index
  if (i < 1 || i > static_cast<long long>(std::numeric_limits<std::uint32_t>::max())) {
    fail(file, "line " + std::to_string(line) + ": face index " + std::string(tok) +
                   " is out of range");
  }
  return static_cast<std::uint32_t>(i - 1);
}

// `v` lines: `x y z`, `x y z w` (w, the weight of rational curves, does not move a polygon's
// vertex: ignored) or `x y z r g b` (MEPP2's colour convention). Other counts are errors: 7
// values could be `x y z w r g b` or `x y z r g b a` (reading either as the other would give
// wrong colours silently), 5 or 8+ fit neither form.
void read_obj_vertex(Tokens& tokens, const std::string& file, std::size_t line, RawMesh& m) {
  constexpr int kMaxValues = 8;  // enough to tell the counts apart
  double v[kMaxValues];
  std::string_view tok;
  int n = 0;
  while (n < kMaxValues && tokens.next(tok)) {
    if (!detail::parse_double(tok, v[n])) {
      fail(file, "line " + std::to_string(line) + ": '" + std::string(tok) + "' is not a number");
    }
    ++n;
  }
  if (n < 3) fail(file, "line " + std::to_string(line) + ": vertex needs x y z");
  if (n != 3 && n != 4 && n != 6) {
    fail(file, "line " + std::to_string(line) + ": a vertex with " +
                   (n == kMaxValues ? "8 or more" : std::to_string(n)) +
                   " values (qm3d reads 'v x y z', 'v x y z w' and 'v x y z r g b'" +
                   (n == 7 ? "; 7 values could be x y z w r g b or x y z r g b a" : "") + ")");
  }
  m.positions.push_back({v[0], v[1], v[2]});
  check_finite(m.positions.back(), m.positions.size() - 1, file);
  m.colors.push_back(n == 6 ? std::optional<Rgb>(Rgb{v[3], v[4], v[5]}) : std::nullopt);
}

RawMesh parse_obj(const std::string& text, const std::string& file) {
  RawMesh m;
  Statements lines(text);
  std::string_view keyword, tok;
  Tokens tokens;
  while (lines.next(keyword, tokens)) {
    if (keyword == "v") {
      read_obj_vertex(tokens, file, lines.line_number(), m);
    } else if (keyword == "f") {
      while (tokens.next(tok)) {
        m.face_indices.push_back(obj_index(tok, m.positions.size(), file, lines.line_number()));
      }
      m.face_offsets.push_back(static_cast<std::uint32_t>(m.face_indices.size()));
    }
    // Other statements (vn, g, o, s, l, p) do not affect the metric; vt, usemtl and mtllib are
    // read by read_textured_obj (texture.h).
  }
  return m;
}

// ---- OFF -------------------------------------------------------------------------------------

struct OffHeader {
  bool texture = false, color = false, normal = false;
};

std::optional<OffHeader> parse_off_keyword(std::string_view kw) {
  OffHeader h;
  if (kw.size() < 3 || kw.substr(kw.size() - 3) != "OFF") return std::nullopt;
  std::string_view prefix = kw.substr(0, kw.size() - 3);
  if (prefix.substr(0, 2) == "ST") { h.texture = true; prefix.remove_prefix(2); }
  if (!prefix.empty() && prefix.front() == 'C') { h.color = true; prefix.remove_prefix(1); }
  if (!prefix.empty() && prefix.front() == 'N') { h.normal = true; prefix.remove_prefix(1); }
  if (!prefix.empty()) return std::nullopt;  // 4OFF, nOFF: not supported
  return h;
}

std::uint64_t off_count(std::string_view tok, const std::string& file) {
  long long n = 0;
  if (!detail::parse_long(tok, n) || n < 0) fail(file, "bad element count '" + std::string(tok) + "'");
  return static_cast<std::uint64_t>(n);
}

void read_off_vertex(std::string_view line, std::size_t line_no, const OffHeader& h,
                     const std::string& file, RawMesh& m) {
  Tokens tokens(line);
  double v[3], normal[3], c[3];
  if (!read_numbers(tokens, v, 3, file, line_no)) {
    fail(file, "line " + std::to_string(line_no) + ": vertex needs x y z");
  }
  m.positions.push_back({v[0], v[1], v[2]});
  check_finite(m.positions.back(), m.positions.size() - 1, file);
  if (h.normal && !read_numbers(tokens, normal, 3, file, line_no)) {
    fail(file, "line " + std::to_string(line_no) + ": vertex needs a normal (NOFF)");
  }
  // COFF: 3 colour values; anything after them (alpha, texture coordinates) is ignored.
  if (h.color && read_numbers(tokens, c, 3, file, line_no)) {
    m.colors.push_back(Rgb{c[0], c[1], c[2]});
  } else {
    m.colors.push_back(std::nullopt);
  }
}

// A triangle line "3 a b c" whose indices are plain decimal digits (at most 10, at most
// 2^32 - 1), read without the general tokenizer: what read_off_face reads from such a line (the
// rest of the line ignored, as there). False, with nothing read, for any other line.
bool read_off_triangle(std::string_view line, RawMesh& m) {
  const char* p = line.data();
  const char* const end = p + line.size();
  const auto skip_blanks = [&] {
    while (p < end && detail::is_blank(*p)) ++p;
  };
  skip_blanks();
  if (p + 1 >= end || p[0] != '3' || !detail::is_blank(p[1])) return false;
  p += 1;
  std::uint32_t idx[3];
  for (std::uint32_t& out : idx) {
    skip_blanks();
    const char* const start = p;
    std::uint64_t value = 0;
    while (p < end && *p >= '0' && *p <= '9' && p - start < 10) value = value * 10 + (*p++ - '0');
    if (p == start || (p < end && !detail::is_blank(*p)) || value > 0xffffffffu) return false;
    out = static_cast<std::uint32_t>(value);
  }
  m.face_indices.insert(m.face_indices.end(), idx, idx + 3);
  m.face_offsets.push_back(static_cast<std::uint32_t>(m.face_indices.size()));
  return true;
}

void read_off_face(std::string_view line, std::size_t line_no, const std::string& file,
                   RawMesh& m) {
  if (read_off_triangle(line, m)) return;
  Tokens tokens(line);
  std::string_view tok;
  long long n = 0;
  if (!tokens.next(tok) || !detail::parse_long(tok, n) || n < 0 || n > 1000000) {
    fail(file, "line " + std::to_string(line_no) + ": bad face vertex count");
  }
  for (long long i = 0; i < n; ++i) {
    long long idx = 0;
    if (!tokens.next(tok)) {
      fail(file, "line " + std::to_string(line_no) + ": face has fewer indices than its count");
    }
    if (!detail::parse_long(tok, idx) || idx < 0 || idx > std::numeric_limits<std::uint32_t>::max()) {
      fail(file, "line " + std::to_string(line_no) + ": bad face index '" + std::string(tok) + "'");
    }
    m.face_indices.push_back(static_cast<std::uint32_t>(idx));
  }
  m.face_offsets.push_back(static_cast<std::uint32_t>(m.face_indices.size()));
}

RawMesh parse_off(const std::string& text, const std::string& file) {
  LineReader lines(text);
  std::string_view line, tok;
  if (!lines.next(line)) fail(file, "empty file");
  Tokens tokens(line);
  tokens.next(tok);
  const auto header = parse_off_keyword(tok);
  if (!header) fail(file, "not an OFF file (first word '" + std::string(tok.substr(0, 20)) + "')");
  std::string_view counts[2];
  int have = 0;
  while (have < 2) {
    if (tokens.next(tok)) {
      counts[have++] = tok;
      continue;
    }
    if (!lines.next(line)) fail(file, "missing vertex and face counts");
    tokens = Tokens(line);
  }
  const std::uint64_t nv = off_count(counts[0], file), nf = off_count(counts[1], file);
  // Each vertex line holds at least "0 0 0\n" and each face line "3 0 0 0\n": a header that
  // claims more than the file can hold fails before anything is allocated.
  if (nv > lines.remaining_bytes() / 6 + 1 || nf > lines.remaining_bytes() / 8 + 1) {
    fail(file, "header declares " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                   " faces but the file is too short to hold them");
  }
  RawMesh m;
  m.positions.reserve(nv);
  m.colors.reserve(nv);
  for (std::uint64_t i = 0; i < nv; ++i) {
    if (!lines.next(line)) fail(file, "file ends after " + std::to_string(i) + " of " + std::to_string(nv) + " vertices");
    read_off_vertex(line, lines.line_number(), *header, file, m);
  }
  for (std::uint64_t f = 0; f < nf; ++f) {
    if (!lines.next(line)) fail(file, "file ends after " + std::to_string(f) + " of " + std::to_string(nf) + " faces");
    read_off_face(line, lines.line_number(), file, m);
  }
  if (lines.next(line)) {
    fail(file, "line " + std::to_string(lines.line_number()) +
                   ": more data than the header's vertex and face counts declare");
  }
  return m;
}

// ---- PLY -------------------------------------------------------------------------------------

RawMesh from_ply(const std::string& bytes, const std::string& file, ColourScale scale) {
  ply::Content c = ply::parse(bytes, file, ply::AsciiFloat::kDouble, scale);
  RawMesh m;
  m.warnings = std::move(c.warnings);
  m.positions = std::move(c.positions);
  m.colors.resize(m.positions.size());
  for (std::size_t i = 0; i < c.colors.size(); ++i) m.colors[i] = c.colors[i];
  m.colors_are_unit_range = true;
  m.face_offsets = std::move(c.face_offsets);
  m.face_indices = std::move(c.face_indices);
  return m;
}

// ---- validation and clean-up -----------------------------------------------------------------

MeshFormat format_of(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  if (ext == "obj") return MeshFormat::kObj;
  if (ext == "off") return MeshFormat::kOff;
  if (ext == "ply") return MeshFormat::kPly;
  fail(path.string(), "unknown mesh format '." + ext + "' (expected .obj, .off or .ply)");
}

RawMesh parse_raw(const std::string& bytes, MeshFormat format, const std::string& name,
                  ColourScale scale) {
  switch (format) {
    case MeshFormat::kObj: return parse_obj(bytes, name);
    case MeshFormat::kOff: return parse_off(bytes, name);
    case MeshFormat::kPly:
      return from_ply(bytes, name, scale);
  }
  fail(name, "unknown mesh format");
}

// Rounds to float precision, as MEPP2 stores colours. The volatile store is deliberate: GCC 12's
// SLP vectorizer drops a plain (double)(float)x round trip when it packs two of them (seen at -O2
// on Debian 12's g++ 12.2), which silently changed scores in the 10th digit.
double to_float_precision(double x) {
  volatile float f = static_cast<float>(x);
  return f;
}

// All vertices or none have colours; returns them in [0, 1] at float precision (MEPP2), the
// scale of OBJ / OFF colours chosen by `scale` (reading.h; its warning added to `warnings`).
std::vector<Rgb> vertex_colors(const RawMesh& m, const std::string& file, ColourScale scale,
                               std::vector<std::string>& warnings) {
  std::size_t missing = 0, first_missing = 0;
  ColourValues values;
  for (std::size_t i = 0; i < m.colors.size(); ++i) {
    if (!m.colors[i]) {
      if (missing++ == 0) first_missing = i;
      continue;
    }
    for (double v : {m.colors[i]->r, m.colors[i]->g, m.colors[i]->b}) {
      if (!(v >= 0.0) || v > 255.5) {
        fail(file, "vertex " + std::to_string(i) + " has colour value " + number_text(v) +
                       " outside [0, 1] and [0, 255]");
      }
      values.add(v);
    }
  }
  if (missing == m.colors.size()) fail(file, "no vertex colours (CMDM and PCQM need a colour per vertex)");
  if (missing > 0) {
    fail(file, "colours missing for " + std::to_string(missing) + " of " +
                   std::to_string(m.colors.size()) + " vertices (first: vertex " +
                   std::to_string(first_missing) + ")");
  }
  // PLY colours arrive in [0, 1] already (their scale was chosen by the PLY reader).
  const ColourConversion from_file =
      m.colors_are_unit_range ? ColourConversion{} : colour_conversion(values, scale, file);
  if (from_file.warning) warnings.push_back(*from_file.warning);
  std::vector<Rgb> out(m.colors.size());
  auto convert = [&from_file](double c) { return to_float_precision(from_file(c)); };
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = {convert(m.colors[i]->r), convert(m.colors[i]->g), convert(m.colors[i]->b)};
  }
  return out;
}

// Triangulates polygons (polygon_triangulation.h); checks indices.
std::vector<Triangle> triangulate(const RawMesh& m, const std::string& file,
                                  std::vector<std::string>& warnings) {
  std::vector<Triangle> tris;
  tris.reserve(m.face_offsets.size());
  std::size_t polygons = 0, large = 0;
  for (std::size_t f = 0; f + 1 < m.face_offsets.size(); ++f) {
    const std::uint32_t begin = m.face_offsets[f], end = m.face_offsets[f + 1];
    if (end - begin < 3) fail(file, "face " + std::to_string(f) + " has fewer than 3 vertices");
    for (std::uint32_t k = begin; k < end; ++k) {
      if (m.face_indices[k] >= m.positions.size()) {
        fail(file, "face " + std::to_string(f) + " refers to vertex " +
                       std::to_string(m.face_indices[k]) + ", but there are " +
                       std::to_string(m.positions.size()) + " vertices");
      }
    }
    if (end - begin > 3) ++polygons;
    if (end - begin > detail::kMaxFanCorners) ++large;
    const std::uint32_t* corner = &m.face_indices[begin];
    detail::triangulate_polygon(end - begin,
                                [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
                                  tris.push_back({corner[a], corner[b], corner[c]});
                                });
  }
  if (polygons > large) {
    warnings.push_back(file + ": " + std::to_string(polygons - large) +
                       " polygons with more than 3 vertices were fan-triangulated");
  }
  if (large > 0) {
    warnings.push_back(file + ": " + std::to_string(large) + " polygons with more than " +
                       std::to_string(detail::kMaxFanCorners) +
                       " vertices were triangulated by halves (a fan of so many slivers is "
                       "degenerate)");
  }
  return tris;
}

// Drops vertices no face uses, renumbering the faces.
void drop_unreferenced(MeshFile& out, const std::string& file) {
  ColoredMesh& mesh = out.mesh;
  std::vector<char> used(mesh.positions.size(), 0);
  for (const auto& t : mesh.triangles) used[t[0]] = used[t[1]] = used[t[2]] = 1;
  const auto unused = static_cast<std::size_t>(std::count(used.begin(), used.end(), 0));
  out.file_vertex.resize(mesh.positions.size());
  for (std::uint32_t i = 0; i < out.file_vertex.size(); ++i) out.file_vertex[i] = i;
  if (unused == 0) return;
  std::vector<std::uint32_t> new_index(mesh.positions.size(), 0);
  std::size_t n = 0;
  const bool colors = !mesh.colors.empty();
  for (std::size_t i = 0; i < used.size(); ++i) {
    if (!used[i]) continue;
    new_index[i] = static_cast<std::uint32_t>(n);
    mesh.positions[n] = mesh.positions[i];
    if (colors) mesh.colors[n] = mesh.colors[i];
    out.file_vertex[n] = static_cast<std::uint32_t>(i);
    ++n;
  }
  mesh.positions.resize(n);
  if (colors) mesh.colors.resize(n);
  out.file_vertex.resize(n);
  for (auto& t : mesh.triangles) {
    for (auto& v : t) v = new_index[v];
  }
  out.warnings.push_back(file + ": dropped " + std::to_string(unused) +
                         " vertices that no face uses");
}

}  // namespace

MeshFile parse_mesh(const std::string& bytes, MeshFormat format, const std::string& file,
                    const MeshReadOptions& options) {
  RawMesh raw = parse_raw(bytes, format, file, options.colour_scale);
  if (raw.positions.empty()) fail(file, "no vertices");
  MeshFile out;
  out.warnings = std::move(raw.warnings);
  const bool has_colors = std::any_of(raw.colors.begin(), raw.colors.end(),
                                      [](const auto& c) { return c.has_value(); });
  if (options.require_colors || has_colors) {
    out.mesh.colors = vertex_colors(raw, file, options.colour_scale, out.warnings);
  }
  out.mesh.triangles = triangulate(raw, file, out.warnings);
  if (out.mesh.triangles.empty()) {
    fail(file, "no faces (a point cloud? score it with `qm3d pcqm`)");
  }
  out.mesh.positions = std::move(raw.positions);
  drop_unreferenced(out, file);
  return out;
}

MeshFile read_mesh(const std::filesystem::path& path, const MeshReadOptions& options) {
  return read_mesh(path, format_of(path), options);
}

MeshFile read_mesh(const std::filesystem::path& path, MeshFormat format,
                   const MeshReadOptions& options) {
  const std::string bytes = read_file_bytes(path);
  // Colours of a textured mesh come from its texture (texture.h); MSDM2 ignores colours.
  if (options.require_colors) {
    ReadOptions read;
    read.colour_scale = options.colour_scale;
    std::vector<std::string> no_texture;
    if (auto textured = read_textured_mesh(bytes, format, path, read, &no_texture)) {
      return std::move(textured->file);
    }
    if (!no_texture.empty()) throw FormatError(no_texture.front());  // colours required
  }
  return parse_mesh(bytes, format, path.string(), options);
}

MeshFile mesh_from_arrays(std::vector<Vec3> positions, std::vector<Rgb> colors,
                          std::vector<Triangle> triangles, const std::string& name) {
  if (positions.empty()) fail(name, "no vertices");
  if (triangles.empty()) fail(name, "no faces (a point cloud? score it with PCQM)");
  if (!colors.empty() && colors.size() != positions.size()) {
    fail(name, std::to_string(positions.size()) + " vertices but " +
                   std::to_string(colors.size()) + " colours");
  }
  for (std::size_t i = 0; i < positions.size(); ++i) check_finite(positions[i], i, name);
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    for (const std::uint32_t v : triangles[f]) {
      if (v >= positions.size()) {
        fail(name, "face " + std::to_string(f) + " refers to vertex " + std::to_string(v) +
                       ", but there are " + std::to_string(positions.size()) + " vertices");
      }
    }
  }
  for (std::size_t i = 0; i < colors.size(); ++i) {
    for (double* c : {&colors[i].r, &colors[i].g, &colors[i].b}) {
      if (!(*c >= 0.0 && *c <= 1.0)) {
        fail(name, "vertex " + std::to_string(i) + " has colour value " + number_text(*c) +
                       " outside [0, 1]");
      }
      *c = to_float_precision(*c);
    }
  }
  MeshFile out;
  out.mesh = ColoredMesh{std::move(positions), std::move(colors), std::move(triangles)};
  drop_unreferenced(out, name);
  return out;
}

ColoredCloud read_mesh_vertices(const std::filesystem::path& path) {
  return read_mesh_vertices_data(path, format_of(path)).cloud;
}

ColoredCloud read_mesh_vertices(const std::filesystem::path& path, MeshFormat format) {
  return read_mesh_vertices_data(path, format).cloud;
}

CloudData read_mesh_vertices_data(const std::filesystem::path& path, MeshFormat format,
                                  const ReadOptions& options) {
  const std::string bytes = read_file_bytes(path);
  std::vector<std::string> no_texture;
  if (auto textured = read_textured_mesh(bytes, format, path, options, &no_texture)) {
    MeshFile& file = textured->file;
    return CloudData{vertex_cloud(file.mesh), std::move(file.warnings), {}};
  }
  RawMesh raw = parse_raw(bytes, format, path.string(), options.colour_scale);
  if (raw.positions.empty()) fail(path.string(), "no vertices");
  CloudData out;
  out.warnings = std::move(raw.warnings);
  out.warnings.insert(out.warnings.end(), no_texture.begin(), no_texture.end());
  out.cloud.colors = vertex_colors(raw, path.string(), options.colour_scale, out.warnings);
  out.cloud.positions = std::move(raw.positions);
  return out;
}

}  // namespace qm3d::mesh
