#include "qm3d/common/ply.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <locale>
#include <optional>
#include <ostream>
#include <sstream>

#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/large_arrays.h"

namespace qm3d::ply {
namespace {

constexpr std::size_t kMaxHeaderBytes = 1 << 20;

[[noreturn]] void fail(const std::string& name, const std::string& what) {
  throw FormatError(name + ": PLY: " + what);
}

std::size_t scalar_size(ScalarType t) {
  switch (t) {
    case ScalarType::kInt8:
    case ScalarType::kUint8:
      return 1;
    case ScalarType::kInt16:
    case ScalarType::kUint16:
      return 2;
    case ScalarType::kInt32:
    case ScalarType::kUint32:
    case ScalarType::kFloat32:
      return 4;
    case ScalarType::kFloat64:
      return 8;
  }
  return 8;
}

bool is_integer_type(ScalarType t) {
  return t != ScalarType::kFloat32 && t != ScalarType::kFloat64;
}

std::optional<ScalarType> parse_type(const std::string& s) {
  if (s == "char" || s == "int8") return ScalarType::kInt8;
  if (s == "uchar" || s == "uint8") return ScalarType::kUint8;
  if (s == "short" || s == "int16") return ScalarType::kInt16;
  if (s == "ushort" || s == "uint16") return ScalarType::kUint16;
  if (s == "int" || s == "int32") return ScalarType::kInt32;
  if (s == "uint" || s == "uint32") return ScalarType::kUint32;
  if (s == "float" || s == "float32") return ScalarType::kFloat32;
  if (s == "double" || s == "float64") return ScalarType::kFloat64;
  return std::nullopt;
}

const char* type_name(ScalarType t) {
  switch (t) {
    case ScalarType::kInt8:
      return "char";
    case ScalarType::kUint8:
      return "uchar";
    case ScalarType::kInt16:
      return "short";
    case ScalarType::kUint16:
      return "ushort";
    case ScalarType::kInt32:
      return "int";
    case ScalarType::kUint32:
      return "uint";
    case ScalarType::kFloat32:
      return "float";
    case ScalarType::kFloat64:
      return "double";
  }
  return "?";
}

// An integral value read from the file, written in full: an ASCII file can hold any number of
// digits, which no integer type holds.
std::string integer_text(double v) {
  char text[400];  // enough for every finite double with %.0f
  std::snprintf(text, sizeof text, "%.0f", v);
  return text;
}

// The values an integer type holds.
std::pair<double, double> integer_range(ScalarType t) {
  switch (t) {
    case ScalarType::kInt8:
      return {-128.0, 127.0};
    case ScalarType::kUint8:
      return {0.0, 255.0};
    case ScalarType::kInt16:
      return {-32768.0, 32767.0};
    case ScalarType::kUint16:
      return {0.0, 65535.0};
    case ScalarType::kInt32:
      return {-2147483648.0, 2147483647.0};
    case ScalarType::kUint32:
      return {0.0, 4294967295.0};
    case ScalarType::kFloat32:
    case ScalarType::kFloat64:
      break;
  }
  return {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
}

std::vector<std::string> split_words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> words;
  std::string w;
  while (in >> w) words.push_back(w);
  return words;
}

std::uint64_t parse_count(const std::string& s, const std::string& name) {
  if (s.empty() || s.size() > 19 || !std::all_of(s.begin(), s.end(), ::isdigit)) {
    fail(name, "bad element count '" + s + "'");
  }
  return std::stoull(s);
}

// Minimal bytes one record of `e` occupies, to bound what a header may claim.
std::uint64_t min_record_bytes(const Element& e, Format format) {
  std::uint64_t bytes = 0;
  for (const auto& p : e.properties) {
    if (format == Format::kAscii) {
      bytes += 2;  // at least one character and one separator
    } else {
      bytes += p.is_list ? scalar_size(p.count_type) : scalar_size(p.type);
    }
  }
  return std::max<std::uint64_t>(bytes, 1);
}

// Sequential reader of the data section, ASCII (line per record) or binary.
class Cursor {
 public:
  Cursor(const std::string& bytes, std::size_t offset, Format format, AsciiFloat ascii_float,
         const std::string& name)
      : data_(bytes.data()),
        size_(bytes.size()),
        pos_(offset),
        format_(format),
        float32_(ascii_float == AsciiFloat::kAsDeclared),
        name_(name),
        line_(1 + static_cast<std::size_t>(std::count(data_, data_ + offset, '\n'))) {}

  void begin_record(const std::string& where) {
    where_ = &where;
    if (format_ != Format::kAscii) return;
    // Skip blank lines, then delimit the record's line.
    while (pos_ < size_ && (data_[pos_] == '\n' || data_[pos_] == '\r' || data_[pos_] == ' ' ||
                            data_[pos_] == '\t')) {
      if (data_[pos_] == '\n') ++line_;
      ++pos_;
    }
    if (pos_ >= size_) fail(name_, "file ends before " + where);
    const void* nl = std::memchr(data_ + pos_, '\n', size_ - pos_);
    line_end_ = nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - data_) : size_;
  }

  void end_record() {
    if (format_ != Format::kAscii) return;
    skip_spaces();
    if (pos_ < line_end_) fail(name_, *where_ + " has more values than the header declares");
    pos_ = line_end_;
  }

  /// The next value of property `p`: one of its items, or the length of its list.
  double value(const Property& p, bool list_length = false) {
    const ScalarType t = list_length ? p.count_type : p.type;
    return format_ == Format::kAscii ? ascii_value(t, p, list_length) : binary_value(t);
  }

  /// Whether ASCII `float` values are rounded to float32 (binary ones always are).
  bool rounds_float32() const { return format_ != Format::kAscii || float32_; }

  /// True when nothing but whitespace follows the current position.
  bool at_end() const {
    for (std::size_t i = pos_; i < size_; ++i) {
      const char c = data_[i];
      if (c != ' ' && c != '\t' && c != '\r' && c != '\n') return false;
    }
    return true;
  }

 private:
  void skip_spaces() {
    while (pos_ < line_end_ && (data_[pos_] == ' ' || data_[pos_] == '\t' || data_[pos_] == '\r')) {
      ++pos_;
    }
  }

  double ascii_value(ScalarType t, const Property& p, bool list_length) {
    skip_spaces();
    if (pos_ >= line_end_) fail(name_, *where_ + " has fewer values than the header declares");
    std::size_t end = pos_;
    while (end < line_end_ && data_[end] != ' ' && data_[end] != '\t' && data_[end] != '\r') ++end;
    const std::string_view token(data_ + pos_, end - pos_);
    double v = 0;
    bool ok = false;
    if (float32_ && t == ScalarType::kFloat32) {
      float f = 0;
      ok = parse_number(token, f);
      v = f;
    } else {
      ok = parse_number(token, v);
    }
    if (!ok) fail(name_, *where_ + ": '" + std::string(token) + "' is not a number");
    if (is_integer_type(t)) check_integer(v, t, token, p, list_length);
    pos_ = end;
    return v;
  }

  // An ASCII integer must be one the declared type holds ("uchar 300" is no colour of 1.18).
  void check_integer(double v, ScalarType t, std::string_view token, const Property& p,
                     bool list_length) {
    const auto [lo, hi] = integer_range(t);
    if (v >= lo && v <= hi && v == std::floor(v)) return;
    const std::string what = (list_length ? "list length of '"
                              : p.is_list ? "item of '"
                                          : "property '") +
                             p.name + "'";
    if (v != std::floor(v) || !std::isfinite(v)) {
      fail(name_, *where_ + " (line " + std::to_string(line_) + "): " + what + " '" +
                      std::string(token) + "' is not an integer (" + type_name(t) + ")");
    }
    if (v < lo || v > hi) {
      fail(name_, *where_ + " (line " + std::to_string(line_) + "): " + what + " " +
                      std::string(token) + " is out of range for " + type_name(t) + " (" +
                      integer_text(lo) + ".." + integer_text(hi) + ")");
    }
  }

  template <typename T>
  T load() {
    T v;
    unsigned char raw[sizeof(T)];
    std::memcpy(raw, data_ + pos_, sizeof(T));
    const bool big = format_ == Format::kBinaryBigEndian;
    if (big) std::reverse(raw, raw + sizeof(T));  // hosts are little endian (x86-64, arm64)
    std::memcpy(&v, raw, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }

  double binary_value(ScalarType t) {
    if (size_ - pos_ < scalar_size(t)) fail(name_, "file is truncated in " + *where_);
    switch (t) {
      case ScalarType::kInt8:
        return load<std::int8_t>();
      case ScalarType::kUint8:
        return load<std::uint8_t>();
      case ScalarType::kInt16:
        return load<std::int16_t>();
      case ScalarType::kUint16:
        return load<std::uint16_t>();
      case ScalarType::kInt32:
        return load<std::int32_t>();
      case ScalarType::kUint32:
        return load<std::uint32_t>();
      case ScalarType::kFloat32:
        return load<float>();
      case ScalarType::kFloat64:
        return load<double>();
    }
    return 0;
  }

  const char* data_;
  std::size_t size_;
  std::size_t pos_;
  std::size_t line_end_ = 0;
  Format format_;
  bool float32_;  // ASCII `float` values parsed as float32
  const std::string& name_;
  const std::string* where_ = nullptr;
  std::size_t line_;  // line number of pos_ (ASCII)
};

struct VertexLayout {
  int x = -1, y = -1, z = -1;
  int red = -1, green = -1, blue = -1;
  int nx = -1, ny = -1, nz = -1;  // all three or none
  int u = -1, v = -1;             // texture coordinates: both or none
};

int find_property(const Element& e, const std::string& name) {
  for (std::size_t i = 0; i < e.properties.size(); ++i) {
    if (e.properties[i].name == name && !e.properties[i].is_list) return static_cast<int>(i);
  }
  return -1;
}

VertexLayout vertex_layout(const Element& e, const std::string& name) {
  VertexLayout l;
  l.x = find_property(e, "x");
  l.y = find_property(e, "y");
  l.z = find_property(e, "z");
  if (l.x < 0 || l.y < 0 || l.z < 0) fail(name, "vertex element has no x, y, z properties");
  const char* names[3][3] = {
      {"red", "green", "blue"}, {"r", "g", "b"}, {"diffuse_red", "diffuse_green", "diffuse_blue"}};
  for (const auto& n : names) {
    const int r = find_property(e, n[0]), g = find_property(e, n[1]), b = find_property(e, n[2]);
    if (r >= 0 && g >= 0 && b >= 0) {
      l.red = r;
      l.green = g;
      l.blue = b;
      break;
    }
  }
  const int nx = find_property(e, "nx"), ny = find_property(e, "ny"), nz = find_property(e, "nz");
  if (nx >= 0 && ny >= 0 && nz >= 0) {
    l.nx = nx;
    l.ny = ny;
    l.nz = nz;
  }
  // MeshLab and mmetric write texture_u / texture_v; s / t and u / v are the other names found.
  const char* uv_names[3][2] = {{"texture_u", "texture_v"}, {"s", "t"}, {"u", "v"}};
  for (const auto& n : uv_names) {
    const int u = find_property(e, n[0]), v = find_property(e, n[1]);
    if (u >= 0 && v >= 0) {
      l.u = u;
      l.v = v;
      break;
    }
  }
  return l;
}

ColorEncoding color_encoding(const Element& e, const VertexLayout& l, const std::string& name) {
  if (l.red < 0) return ColorEncoding::kNone;
  const ScalarType t = e.properties[l.red].type;
  if (e.properties[l.green].type != t || e.properties[l.blue].type != t) {
    fail(name, "colour channels have different types");
  }
  switch (t) {
    case ScalarType::kUint8:
      return ColorEncoding::kUint8;
    case ScalarType::kUint16:
      return ColorEncoding::kUint16;
    case ScalarType::kFloat32:
    case ScalarType::kFloat64:
      return ColorEncoding::kFloat;
    default:
      fail(name, std::string("unsupported colour type '") + type_name(t) +
                     "' (expected uchar, ushort or float)");
  }
}

void read_vertices(Cursor& cur, const Element& e, const std::string& name, Content& out) {
  const VertexLayout l = vertex_layout(e, name);
  out.color_encoding = color_encoding(e, l, name);
  reserve_with_huge_pages(out.positions, e.count);
  out.positions.resize(e.count);
  if (out.color_encoding != ColorEncoding::kNone) {
    reserve_with_huge_pages(out.colors, e.count);
    out.colors.resize(e.count);
  }
  if (l.nx >= 0) out.normals.resize(e.count);
  if (l.u >= 0) out.uvs.resize(e.count);
  std::vector<double> values(e.properties.size());
  std::string where;
  for (std::uint64_t i = 0; i < e.count; ++i) {
    where = "vertex " + std::to_string(i);
    cur.begin_record(where);
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const Property& p = e.properties[k];
      if (p.is_list) {
        const double n = cur.value(p, true);
        if (n < 0) fail(name, where + ": negative list length");
        for (double j = 0; j < n; ++j) cur.value(p);
        values[k] = 0;
      } else {
        values[k] = cur.value(p);
      }
    }
    cur.end_record();
    out.positions[i] = {values[l.x], values[l.y], values[l.z]};
    if (!std::isfinite(values[l.x]) || !std::isfinite(values[l.y]) || !std::isfinite(values[l.z])) {
      fail(name, where + " has a non-finite coordinate");
    }
    if (out.color_encoding != ColorEncoding::kNone) {
      out.colors[i] = {values[l.red], values[l.green], values[l.blue]};
    }
    if (l.nx >= 0) out.normals[i] = {values[l.nx], values[l.ny], values[l.nz]};
    if (l.u >= 0) {
      out.uvs[i] = {values[l.u], values[l.v]};
      if (!std::isfinite(out.uvs[i][0]) || !std::isfinite(out.uvs[i][1])) {
        fail(name, where + " has a non-finite texture coordinate");
      }
    }
  }
}

// Integer colours use their type's range; float colours the ColourScale (reading.h).
void normalise_colors(Content& c, const std::string& name, ColourScale colour_scale) {
  if (c.color_encoding == ColorEncoding::kUint8 || c.color_encoding == ColorEncoding::kUint16) {
    const double scale = c.color_encoding == ColorEncoding::kUint8 ? 255.0 : 65535.0;
    for (Rgb& rgb : c.colors) {
      for (double* v : {&rgb.r, &rgb.g, &rgb.b}) *v /= scale;
    }
    return;
  }
  if (c.color_encoding != ColorEncoding::kFloat) return;
  ColourValues values;
  for (std::size_t i = 0; i < c.colors.size(); ++i) {
    for (double v : {c.colors[i].r, c.colors[i].g, c.colors[i].b}) {
      if (!(v >= 0.0) || v > 255.5) {
        fail(name, "vertex " + std::to_string(i) + " has colour value " + number_text(v) +
                       " outside [0, 1] and [0, 255]");
      }
      values.add(v);
    }
  }
  const ColourConversion convert = colour_conversion(values, colour_scale, name);
  if (convert.warning) c.warnings.push_back(*convert.warning);
  for (Rgb& rgb : c.colors) {
    for (double* v : {&rgb.r, &rgb.g, &rgb.b}) *v = convert(*v);
  }
}

int face_list_property(const Element& e) {
  for (std::size_t i = 0; i < e.properties.size(); ++i) {
    const auto& p = e.properties[i];
    if (p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

int face_property(const Element& e, const std::string& name, bool list) {
  for (std::size_t i = 0; i < e.properties.size(); ++i) {
    if (e.properties[i].name == name && e.properties[i].is_list == list) return int(i);
  }
  return -1;
}

// One value of a face record: a vertex index of the face list, a texture coordinate of the
// `texcoord` list, or something else (skipped).
void read_face_value(Cursor& cur, const Property& p, int k, int list, int texcoord,
                     const std::string& where, const std::string& name, Content& out) {
  const double value = cur.value(p);
  if (k == texcoord) {
    if (!std::isfinite(value)) fail(name, where + " has a non-finite texture coordinate");
    out.face_texcoords.push_back(value);
  }
  if (k != list) return;
  if (value < 0 || value >= static_cast<double>(out.positions.size())) {
    fail(name, where + " refers to vertex " + integer_text(value) + ", but there are " +
                   std::to_string(out.positions.size()) + " vertices");
  }
  out.face_indices.push_back(static_cast<std::uint32_t>(value));
}

void read_faces(Cursor& cur, const Element& e, const std::string& name, Content& out) {
  const int list = face_list_property(e);
  const int texcoord = face_property(e, "texcoord", true);
  const int texnumber = face_property(e, "texnumber", false);
  out.face_offsets.assign(1, 0);
  out.face_offsets.reserve(e.count + 1);
  std::string where;
  for (std::uint64_t f = 0; f < e.count; ++f) {
    where = "face " + std::to_string(f);
    cur.begin_record(where);
    double corners = 0, texcoords = 0;
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const Property& p = e.properties[k];
      if (!p.is_list) {
        const double value = cur.value(p);
        if (static_cast<int>(k) == texnumber) out.face_texnumbers.push_back(std::int64_t(value));
        continue;
      }
      const double n = cur.value(p, true);
      if (n < 0) fail(name, where + ": negative list length");
      for (double j = 0; j < n; ++j)
        read_face_value(cur, p, int(k), list, texcoord, where, name, out);
      if (static_cast<int>(k) == list) corners = n;
      if (static_cast<int>(k) == texcoord) texcoords = n;
    }
    if (list >= 0 && corners < 3) {
      fail(name,
           where + " has " + std::to_string(static_cast<int>(corners)) + " vertices (need 3)");
    }
    if (list >= 0 && texcoord >= 0 && texcoords != 2 * corners) {
      fail(name, where + " has " + integer_text(texcoords) + " texcoord values for " +
                     integer_text(corners) + " vertices (need u v for each)");
    }
    cur.end_record();
    if (list >= 0) out.face_offsets.push_back(static_cast<std::uint32_t>(out.face_indices.size()));
  }
}

void skip_element(Cursor& cur, const Element& e, const std::string& name) {
  std::string where;
  for (std::uint64_t i = 0; i < e.count; ++i) {
    where = e.name + " " + std::to_string(i);
    cur.begin_record(where);
    for (const auto& p : e.properties) {
      if (p.is_list) {
        const double n = cur.value(p, true);
        if (n < 0) fail(name, where + ": negative list length");
        for (double j = 0; j < n; ++j) cur.value(p);
      } else {
        cur.value(p);
      }
    }
    cur.end_record();
  }
}

}  // namespace

Header parse_header(const std::string& bytes, const std::string& name,
                    std::optional<std::uint64_t> file_size) {
  if (bytes.size() < 4 || bytes.compare(0, 3, "ply") != 0 ||
      (bytes[3] != '\n' && bytes[3] != '\r')) {
    fail(name, "not a PLY file (missing 'ply' magic)");
  }
  const std::size_t end = bytes.find("end_header", 0);
  if (end == std::string::npos || end > kMaxHeaderBytes) fail(name, "no end_header line");
  std::size_t data = bytes.find('\n', end);
  data = data == std::string::npos ? bytes.size() : data + 1;
  Header h;
  bool have_format = false;
  std::istringstream lines(bytes.substr(0, end));
  std::string line;
  std::getline(lines, line);  // magic
  while (std::getline(lines, line)) {
    const auto w = split_words(line);
    if (w.size() >= 3 && w[0] == "comment" && w[1] == "TextureFile") {
      const std::size_t at = line.find("TextureFile") + std::string("TextureFile").size();
      std::string file = line.substr(at);
      file.erase(0, file.find_first_not_of(" \t"));
      file.erase(file.find_last_not_of(" \t\r") + 1);
      h.texture_files.push_back(file);
      continue;
    }
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "format") {
      if (w.size() < 2) fail(name, "bad format line");
      if (w[1] == "ascii")
        h.format = Format::kAscii;
      else if (w[1] == "binary_little_endian")
        h.format = Format::kBinaryLittleEndian;
      else if (w[1] == "binary_big_endian")
        h.format = Format::kBinaryBigEndian;
      else
        fail(name, "unknown format '" + w[1] + "'");
      have_format = true;
    } else if (w[0] == "element") {
      if (w.size() != 3) fail(name, "bad element line '" + line + "'");
      h.elements.push_back(Element{w[1], parse_count(w[2], name), {}});
    } else if (w[0] == "property") {
      if (h.elements.empty()) fail(name, "property before any element");
      Property p;
      if (w.size() == 5 && w[1] == "list") {
        const auto ct = parse_type(w[2]), it = parse_type(w[3]);
        if (!ct || !it || !is_integer_type(*ct)) fail(name, "bad list property '" + line + "'");
        p = Property{w[4], *it, true, *ct};
      } else if (w.size() == 3) {
        const auto t = parse_type(w[1]);
        if (!t) fail(name, "unknown property type '" + w[1] + "'");
        p = Property{w[2], *t, false, ScalarType::kUint8};
      } else {
        fail(name, "bad property line '" + line + "'");
      }
      h.elements.back().properties.push_back(p);
    } else {
      fail(name, "unexpected header line '" + line + "'");
    }
  }
  if (!have_format) fail(name, "no format line");
  h.data_offset = data;
  // A header may not claim more records than the data section can hold (checked before any
  // allocation, so a corrupt count fails fast).
  const std::uint64_t size = file_size.value_or(bytes.size());
  std::uint64_t available = size - std::min<std::uint64_t>(size, data);
  for (const auto& e : h.elements) {
    const std::uint64_t per = min_record_bytes(e, h.format);
    if (e.count > 0 && e.properties.empty()) fail(name, "element " + e.name + " has no properties");
    if (e.count > (available + 1) / per) {
      fail(name, "header declares " + std::to_string(e.count) + " " + e.name +
                     " elements but the file is too short to hold them");
    }
    available -= std::min(available, e.count * per);
  }
  return h;
}

// Positions declared `float` and held as float32 by the reader may have lost their detail.
void warn_of_float32_rounding(const Element& vertex, const Cursor& cur, const std::string& name,
                              Content& out) {
  const VertexLayout l = vertex_layout(vertex, name);
  bool float32 = false;
  for (const int k : {l.x, l.y, l.z}) {
    float32 = float32 || vertex.properties[k].type == ScalarType::kFloat32;
  }
  if (!float32 || !cur.rounds_float32()) return;
  if (auto w = float32_rounding_warning(out.positions, name)) out.warnings.push_back(*w);
}

Content parse(const std::string& bytes, const std::string& name, AsciiFloat ascii_float,
              ColourScale colour_scale) {
  const Header h = parse_header(bytes, name);
  Content out;
  out.texture_files = h.texture_files;
  Cursor cur(bytes, h.data_offset, h.format, ascii_float, name);
  bool have_vertices = false;
  for (const auto& e : h.elements) {
    if (e.name == "vertex" && !have_vertices) {
      read_vertices(cur, e, name, out);
      warn_of_float32_rounding(e, cur, name, out);
      have_vertices = true;
    } else if (e.name == "face" && have_vertices && face_list_property(e) >= 0) {
      read_faces(cur, e, name, out);
    } else {
      skip_element(cur, e, name);
    }
  }
  if (!have_vertices) fail(name, "no vertex element");
  if (!cur.at_end()) {
    fail(name, "data continues after the elements the header declares (wrong element count?)");
  }
  normalise_colors(out, name, colour_scale);
  return out;
}

Content read(const std::filesystem::path& path, AsciiFloat ascii_float, ColourScale colour_scale) {
  return parse(read_file_bytes(path), path.string(), ascii_float, colour_scale);
}

namespace {

template <typename T>
void put(std::ostream& out, T v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof(T));
}

}  // namespace

void write(const std::filesystem::path& path, const WriteData& d) {
  if (!d.colors.empty() && d.colors.size() != d.positions.size()) {
    throw std::invalid_argument("ply::write: colour count differs from vertex count");
  }
  if (!d.scalar_names.empty() && d.scalars.size() != d.positions.size()) {
    throw std::invalid_argument("ply::write: scalar count differs from vertex count");
  }
  for (const auto& [name, values] : d.extra_scalars) {
    if (values.size() != d.positions.size()) {
      throw std::invalid_argument("ply::write: " + name + " count differs from vertex count");
    }
  }
  if (d.format == Format::kBinaryBigEndian) {
    throw std::invalid_argument("ply::write: big-endian output is not supported");
  }
  const bool ascii = d.format == Format::kAscii;
  write_file_atomically(path, [&](std::ostream& out) {
    out.imbue(std::locale::classic());  // "0.5" whatever the program's global locale
    out << "ply\nformat " << (ascii ? "ascii" : "binary_little_endian") << " 1.0\n"
        << "comment written by qm3d\n"
        << "element vertex " << d.positions.size() << "\n";
    const char* ptype = d.double_positions ? "double" : "float";
    out << "property " << ptype << " x\nproperty " << ptype << " y\nproperty " << ptype << " z\n";
    if (!d.colors.empty()) out << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    for (const std::string& name : d.scalar_names) out << "property float " << name << "\n";
    for (const auto& extra : d.extra_scalars) out << "property float " << extra.first << "\n";
    if (!d.triangles.empty()) {
      out << "element face " << d.triangles.size() << "\nproperty list uchar int vertex_indices\n";
    }
    out << "end_header\n";
    out.precision(17);
    for (std::size_t i = 0; i < d.positions.size(); ++i) {
      const Vec3& p = d.positions[i];
      if (ascii) {
        out << p[0] << ' ' << p[1] << ' ' << p[2];
        if (!d.colors.empty()) {
          out << ' ' << int(d.colors[i][0]) << ' ' << int(d.colors[i][1]) << ' '
              << int(d.colors[i][2]);
        }
        for (std::size_t k = 0; k < d.scalar_names.size(); ++k) out << ' ' << d.scalars[i];
        for (const auto& extra : d.extra_scalars) out << ' ' << extra.second[i];
        out << '\n';
        continue;
      }
      for (double c : p) {
        if (d.double_positions)
          put<double>(out, c);
        else
          put<float>(out, static_cast<float>(c));
      }
      if (!d.colors.empty()) out.write(reinterpret_cast<const char*>(d.colors[i].data()), 3);
      for (std::size_t k = 0; k < d.scalar_names.size(); ++k) put<float>(out, d.scalars[i]);
      for (const auto& extra : d.extra_scalars) put<float>(out, extra.second[i]);
    }
    for (const Triangle& t : d.triangles) {
      if (ascii) {
        out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
        continue;
      }
      put<std::uint8_t>(out, 3);
      for (auto idx : t) put<std::int32_t>(out, static_cast<std::int32_t>(idx));
    }
  });
}

}  // namespace qm3d::ply
