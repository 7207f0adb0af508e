#include "pcd_io.h"

#include <lzf.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/reading.h"

namespace qm3d::pointcloud::detail {
namespace {

/// An 8-bit channel as MEPP-team/PCQM converts it (`RGBtoXYZ`: `_R / 255.0`).
constexpr double kChannelMax = 255.0;

void require_readable(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InputError(path.string() + ": not found or not a regular file");
  }
  std::ifstream probe(path, std::ios::binary);
  if (!probe) throw InputError(path.string() + ": cannot be opened for reading");
}

// A PCD header as the PCD v0.7 format defines it, read strictly: PCL's own header reader
// throws, corrupts memory or allocates from the counts on malformed headers (found by fuzz_pcd
// when PCL still read qm3d's PCD files).
struct PcdLayout {
  std::vector<std::string> fields;
  std::vector<std::uintmax_t> sizes, counts;
  std::vector<std::string> types;
  std::uintmax_t width = 0, height = 0, points = 0, header_bytes = 0;
  std::string data;
};

std::uintmax_t header_count(const std::string& w, const std::filesystem::path& path,
                            const std::string& key) {
  const bool digits =
      !w.empty() && w.size() < 12 &&
      std::all_of(w.begin(), w.end(), [](unsigned char c) { return std::isdigit(c); });
  if (!digits) throw FormatError(path.string() + ": PCD " + key + ": '" + w + "' is not a count");
  return std::stoull(w);
}

void header_line(PcdLayout& l, const std::string& key, const std::vector<std::string>& words,
                 const std::filesystem::path& path) {
  auto counts = [&] {
    std::vector<std::uintmax_t> v;
    for (const auto& w : words) v.push_back(header_count(w, path, key));
    return v;
  };
  if (key == "VERSION" || key == "VIEWPOINT") return;
  if (key == "FIELDS")
    l.fields = words;
  else if (key == "SIZE")
    l.sizes = counts();
  else if (key == "TYPE")
    l.types = words;
  else if (key == "COUNT")
    l.counts = counts();
  else if (key == "WIDTH" && words.size() == 1)
    l.width = header_count(words[0], path, key);
  else if (key == "HEIGHT" && words.size() == 1)
    l.height = header_count(words[0], path, key);
  else if (key == "POINTS" && words.size() == 1)
    l.points = header_count(words[0], path, key);
  else if (key == "DATA" && words.size() == 1)
    l.data = words[0];
  else
    throw FormatError(path.string() + ": not a PCD file (unexpected header line '" + key + "')");
}

void check_layout(const PcdLayout& l, const std::filesystem::path& path) {
  const auto fail = [&](const std::string& what) {
    throw FormatError(path.string() + ": PCD header: " + what);
  };
  const std::size_t n = l.fields.size();
  if (n == 0 || n > 256) fail("FIELDS missing or too many");
  if (l.sizes.size() != n || l.types.size() != n)
    fail("SIZE and TYPE must have one entry per field");
  if (!l.counts.empty() && l.counts.size() != n) fail("COUNT must have one entry per field");
  for (std::size_t f = 0; f < n; ++f) {
    const auto size = l.sizes[f];
    const bool valid_type =
        l.types[f] == "I" || l.types[f] == "U" || (l.types[f] == "F" && (size == 4 || size == 8));
    if (!(size == 1 || size == 2 || size == 4 || size == 8) || !valid_type) {
      fail("field '" + l.fields[f] + "' has SIZE " + std::to_string(size) + " and TYPE " +
           l.types[f]);
    }
    if (!l.counts.empty() && (l.counts[f] < 1 || l.counts[f] > 4096)) {
      fail("field '" + l.fields[f] + "' has COUNT " + std::to_string(l.counts[f]));
    }
  }
  if (l.data != "ascii" && l.data != "binary" && l.data != "binary_compressed") {
    fail("DATA must be ascii, binary or binary_compressed");
  }
  if (l.width * l.height != l.points) fail("POINTS differs from WIDTH x HEIGHT");
}

PcdLayout read_pcd_layout(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  PcdLayout l;
  std::string line;
  while (l.data.empty() && l.header_bytes < (1u << 16) && std::getline(in, line)) {
    l.header_bytes += line.size() + 1;
    std::istringstream words(line);
    std::string key;
    if (!(words >> key) || key[0] == '#') continue;
    std::vector<std::string> rest;
    for (std::string w; words >> w;) rest.push_back(w);
    header_line(l, key, rest, path);
  }
  if (l.data.empty()) throw FormatError(path.string() + ": not a PCD file (no DATA line)");
  check_layout(l, path);
  return l;
}

std::uintmax_t field_count(const PcdLayout& l, std::size_t f) {
  return l.counts.empty() ? 1 : l.counts[f];
}

/// The bytes one point takes of field f (SIZE x COUNT).
std::uintmax_t field_bytes(const PcdLayout& l, std::size_t f) {
  return l.sizes[f] * field_count(l, f);
}

// The byte size of one point record, and the number of ASCII values per line.
std::uintmax_t point_bytes(const PcdLayout& l) {
  std::uintmax_t bytes = 0;
  for (std::size_t f = 0; f < l.fields.size(); ++f) bytes += field_bytes(l, f);
  return bytes;
}

std::uintmax_t values_per_point(const PcdLayout& l) {
  std::uintmax_t values = 0;
  for (std::size_t f = 0; f < l.fields.size(); ++f) values += field_count(l, f);
  return values;
}

// Where the fields qm3d reads are: their field index and their first ASCII column.
struct PcdColumns {
  std::size_t field[4] = {0, 0, 0, 0};  // x, y, z, rgb (or rgba)
  std::size_t column[4] = {0, 0, 0, 0};
  std::size_t columns = 0;  // values per ASCII line (a field of COUNT n takes n)
  bool colour = true;       // an rgb / rgba field (without: no colours, as a colourless PLY)
};

std::optional<std::size_t> layout_field(const PcdLayout& l, const std::string& name) {
  for (std::size_t f = 0; f < l.fields.size(); ++f) {
    if (l.fields[f] == name) return f;
  }
  return std::nullopt;
}

// The fields x, y, z (float or double) and rgb / rgba (4 bytes), each of COUNT 1.
PcdColumns pcd_columns(const PcdLayout& l, const std::filesystem::path& path) {
  PcdColumns c;
  const char* names[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    const auto f = layout_field(l, names[a]);
    if (!f) throw FormatError(path.string() + ": PCD has no '" + names[a] + "' field");
    if (l.types[*f] != "F") {
      throw FormatError(path.string() + ": PCD field '" + names[a] + "' is not float or double");
    }
    c.field[a] = *f;
  }
  auto rgb = layout_field(l, "rgb");
  if (!rgb) rgb = layout_field(l, "rgba");
  // A cloud without colours reads as a colourless PLY does: the metrics that need colours say
  // so (require_colours), the others (psnr --no-color, sample) take its points.
  c.colour = rgb.has_value();
  if (!rgb) rgb = c.field[0];
  if (c.colour && l.sizes[*rgb] != 4) {
    throw FormatError(path.string() + ": PCD field '" + l.fields[*rgb] +
                      "' is not a packed 4-byte colour");
  }
  c.field[3] = *rgb;
  for (const std::size_t f : c.field) {
    if (field_count(l, f) != 1) {
      throw FormatError(path.string() + ": PCD field '" + l.fields[f] + "' has COUNT " +
                        std::to_string(field_count(l, f)) +
                        " (x, y, z and rgb / rgba hold one value each)");
    }
  }
  std::vector<std::size_t> first_column(l.fields.size());
  for (std::size_t f = 0; f < l.fields.size(); ++f) {
    first_column[f] = c.columns;
    c.columns += field_count(l, f);
  }
  for (int k = 0; k < 4; ++k) c.column[k] = first_column[c.field[k]];
  return c;
}

/// A packed colour's 4 bytes hold 0x(AA)RRGGBB (PCL's PointXYZRGB / PointXYZRGBA).
Rgb unpack_colour(std::uint32_t bits) {
  return Rgb{((bits >> 16) & 0xffu) / kChannelMax, ((bits >> 8) & 0xffu) / kChannelMax,
             (bits & 0xffu) / kChannelMax};
}

// ---- ascii --------------------------------------------------------------------------------

// One line of an ASCII PCD split into its values.
class PcdLine {
 public:
  PcdLine(const std::filesystem::path& path, std::size_t line) : path_(path), line_(line) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw FormatError(path_.string() + ": line " + std::to_string(line_) + ": " + what);
  }

  void split(std::string_view text) {
    tokens_.clear();
    std::size_t i = 0;
    while (i < text.size()) {
      while (i < text.size() && is_space(text[i])) ++i;
      const std::size_t begin = i;
      while (i < text.size() && !is_space(text[i])) ++i;
      if (i > begin) tokens_.push_back(text.substr(begin, i - begin));
    }
  }

  std::size_t size() const { return tokens_.size(); }

  template <typename T>
  T number(std::size_t column) const {
    T v{};
    if (!parse_number(tokens_[column], v)) not_a(column, "a number");
    return v;
  }

  template <typename T>
  T integer(std::size_t column) const {
    const std::string_view t = tokens_[column];
    T v{};
    const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    if (r.ec != std::errc() || r.ptr != t.data() + t.size()) not_a(column, "a 32-bit integer");
    return v;
  }

 private:
  static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r'; }
  [[noreturn]] void not_a(std::size_t column, const char* what) const {
    fail("'" + std::string(tokens_[column]) + "' (value " + std::to_string(column + 1) +
         ") is not " + what);
  }

  const std::filesystem::path& path_;
  std::size_t line_;
  std::vector<std::string_view> tokens_;
};

// A packed colour as the ASCII line writes it: TYPE F a float whose bits are 0x00RRGGBB (what
// PCL reads; PCL 1.13 itself writes rgb as TYPE U), U / I the integer.
Rgb ascii_packed_colour(const PcdLine& line, std::size_t column, const std::string& type) {
  std::uint32_t bits = 0;
  if (type == "F") {
    const float f = line.number<float>(column);
    std::memcpy(&bits, &f, sizeof bits);
  } else if (type == "U") {
    bits = line.integer<std::uint32_t>(column);
  } else {
    bits = static_cast<std::uint32_t>(line.integer<std::int32_t>(column));
  }
  return unpack_colour(bits);
}

void read_ascii_point(const PcdLine& line, const PcdLayout& l, const PcdColumns& c, Vec3& position,
                      Rgb& colour) {
  if (line.size() != c.columns) {
    line.fail(std::to_string(line.size()) + " values, but FIELDS and COUNT declare " +
              std::to_string(c.columns));
  }
  for (std::size_t k = 0; k < line.size(); ++k) line.number<double>(k);  // every value a number
  for (int a = 0; a < 3; ++a) {
    const std::size_t column = c.column[a];
    position[a] =
        l.sizes[c.field[a]] == 4 ? double(line.number<float>(column)) : line.number<double>(column);
  }
  if (c.colour) colour = ascii_packed_colour(line, c.column[3], l.types[c.field[3]]);
}

// PCL reads a line with a value too many or too few, or data beyond POINTS, without a word
// (points at (0,0,0), black, or dropped): here each is an error naming the line. Numbers are
// parsed as their SIZE says (float32 or double), as PCL does, whatever the C locale.
ColoredCloud read_ascii_pcd(const std::string& bytes, const PcdLayout& l, const PcdColumns& c,
                            const std::filesystem::path& path) {
  ColoredCloud out;
  out.positions.resize(l.points);
  out.colors.resize(l.points);
  std::size_t n = 0, line_no = 1 + static_cast<std::size_t>(std::count(
                                       bytes.begin(), bytes.begin() + l.header_bytes, '\n'));
  for (std::size_t pos = l.header_bytes; pos < bytes.size(); ++line_no) {
    const std::size_t end = std::min(bytes.find('\n', pos), bytes.size());
    const std::string_view text(bytes.data() + pos, end - pos);
    pos = end + 1;
    PcdLine line(path, line_no);
    line.split(text);
    if (line.size() == 0) continue;
    if (n == l.points) {
      line.fail("more points than POINTS " + std::to_string(l.points) + " declares");
    }
    read_ascii_point(line, l, c, out.positions[n], out.colors[n]);
    ++n;
  }
  if (!c.colour) out.colors.clear();
  if (n < l.points) {
    throw FormatError(path.string() + ": PCD data ends after " + std::to_string(n) + " of the " +
                      std::to_string(l.points) + " points POINTS declares");
  }
  return out;
}

// ---- sizes, checked before anything is allocated from the header's counts -----------------

/// LZF (PCL's binary_compressed) writes at least 3 bytes for a back reference of up to 264
/// bytes: no stream expands more than 88-fold.
constexpr std::uintmax_t kLzfMaxExpansion = 88;

// binary_compressed: the data starts with the compressed and uncompressed byte sizes. The
// uncompressed size must be POINTS x point size, the compressed one must fit in the file, and
// the one must be reachable from the other.
void check_compressed_sizes(const PcdLayout& l, std::uintmax_t body,
                            const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(l.header_bytes));
  std::uint32_t sizes[2] = {0, 0};
  in.read(reinterpret_cast<char*>(sizes), sizeof sizes);
  if (!in) throw FormatError(path.string() + ": PCD binary_compressed data is truncated");
  const std::uintmax_t compressed = sizes[0], uncompressed = sizes[1];
  const std::uintmax_t expected = l.points * point_bytes(l);
  if (uncompressed != expected) {
    throw FormatError(path.string() + ": PCD binary_compressed data claims " +
                      std::to_string(uncompressed) + " bytes uncompressed, but POINTS " +
                      std::to_string(l.points) + " x " + std::to_string(point_bytes(l)) +
                      " bytes per point is " + std::to_string(expected));
  }
  if (compressed + 8 > body || uncompressed > compressed * kLzfMaxExpansion) {
    throw FormatError(path.string() + ": PCD binary_compressed data claims " +
                      std::to_string(compressed) + " compressed bytes, but the file holds " +
                      std::to_string(body >= 8 ? body - 8 : 0) + " after the header (truncated?)");
  }
}

// A binary PCD holds POINTS records, then nothing but zeros (PCL's writer pads its files with up
// to a page of zeros): other bytes after the records are points POINTS does not count.
void check_binary_size(const PcdLayout& l, std::uintmax_t body, const std::filesystem::path& path) {
  const std::uintmax_t records = l.points * point_bytes(l);
  const auto fail = [&](const std::string& what) {
    throw FormatError(path.string() + ": PCD header declares " + std::to_string(l.points) +
                      " points of " + std::to_string(point_bytes(l)) + " bytes, but the file " +
                      what + " (" + std::to_string(body) + " data bytes)");
  };
  if (records > body) fail("is too short to hold them");
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(l.header_bytes + records));
  char chunk[4096];
  while (in.read(chunk, sizeof chunk) || in.gcount() > 0) {
    const auto n = static_cast<std::size_t>(in.gcount());
    if (std::any_of(chunk, chunk + n, [](char c) { return c != 0; })) {
      fail("holds more data after them");
    }
  }
}

// Refuse counts the file cannot hold before anything is allocated (binary: exact size;
// binary_compressed: the sizes its data claims; ASCII: at least two characters per value).
void validate_pcd_sizes(const PcdLayout& l, const std::filesystem::path& path) {
  const std::uintmax_t file_size = std::filesystem::file_size(path);
  const std::uintmax_t body = file_size > l.header_bytes ? file_size - l.header_bytes : 0;
  if (l.points == 0) return;
  if (l.data == "ascii" && l.points * 2 * values_per_point(l) > body + 1) {
    throw FormatError(path.string() + ": PCD header declares " + std::to_string(l.points) +
                      " points but the file is too short to hold them");
  }
  if (l.data == "binary") check_binary_size(l, body, path);
  if (l.data == "binary_compressed") check_compressed_sizes(l, body, path);
}

// ---- binary and binary_compressed ---------------------------------------------------------

/// Where field f's value of point i lies in the (uncompressed) data: at first + i * stride.
struct FieldPlace {
  std::uintmax_t first = 0;
  std::uintmax_t stride = 0;
};

// binary: one record per point, the fields at their offsets in FIELDS order.
FieldPlace record_place(const PcdLayout& l, std::size_t f) {
  FieldPlace p{0, point_bytes(l)};
  for (std::size_t g = 0; g < f; ++g) p.first += field_bytes(l, g);
  return p;
}

// binary_compressed: PCL's writer stores each field for every point in turn (xx..yy..zz..),
// leaving padding fields (named "_") out.
FieldPlace block_place(const PcdLayout& l, std::size_t f) {
  FieldPlace p{0, field_bytes(l, f)};
  for (std::size_t g = 0; g < f; ++g) {
    if (l.fields[g] != "_") p.first += l.points * field_bytes(l, g);
  }
  return p;
}

template <typename T>
T load(const std::uint8_t* at) {
  T v;
  std::memcpy(&v, at, sizeof v);
  return v;
}

ColoredCloud decode_points(const std::uint8_t* data, const PcdLayout& l, const PcdColumns& c,
                           FieldPlace (*place)(const PcdLayout&, std::size_t)) {
  FieldPlace at[4];
  for (int k = 0; k < 4; ++k) at[k] = place(l, c.field[k]);
  ColoredCloud out;
  out.positions.resize(l.points);
  out.colors.resize(l.points);
  for (std::size_t i = 0; i < l.points; ++i) {
    for (int a = 0; a < 3; ++a) {
      const std::uint8_t* v = data + at[a].first + i * at[a].stride;
      out.positions[i][a] = l.sizes[c.field[a]] == 8 ? load<double>(v) : double(load<float>(v));
    }
    if (c.colour) {
      out.colors[i] = unpack_colour(load<std::uint32_t>(data + at[3].first + i * at[3].stride));
    }
  }
  if (!c.colour) out.colors.clear();
  return out;
}

// `bytes` is the file read after validate_pcd_sizes; it is checked again in case the file
// changed in between.
void require_data_bytes(const std::string& bytes, std::uintmax_t needed, const PcdLayout& l,
                        const std::filesystem::path& path) {
  if (bytes.size() < l.header_bytes + needed) {
    throw FormatError(path.string() + ": PCD data shorter than its header declares (the file " +
                      "changed while it was read?)");
  }
}

ColoredCloud read_binary_pcd(const std::string& bytes, const PcdLayout& l, const PcdColumns& c,
                             const std::filesystem::path& path) {
  require_data_bytes(bytes, l.points * point_bytes(l), l, path);
  const auto* data = reinterpret_cast<const std::uint8_t*>(bytes.data()) + l.header_bytes;
  return decode_points(data, l, c, record_place);
}

ColoredCloud read_compressed_pcd(const std::string& bytes, const PcdLayout& l, const PcdColumns& c,
                                 const std::filesystem::path& path) {
  if (layout_field(l, "_")) {  // PCL writes none, and reads the stored size inconsistently
    throw FormatError(path.string() + ": PCD binary_compressed data with a padding field '_' " +
                      "is not supported");
  }
  require_data_bytes(bytes, 8, l, path);
  const char* data = bytes.data() + l.header_bytes;
  const std::uint32_t compressed = load<std::uint32_t>(reinterpret_cast<const std::uint8_t*>(data));
  const std::uint32_t uncompressed =
      load<std::uint32_t>(reinterpret_cast<const std::uint8_t*>(data + 4));
  require_data_bytes(bytes, 8 + std::uintmax_t(compressed), l, path);
  std::vector<std::uint8_t> fields(uncompressed);
  const unsigned int got = lzf_decompress(data + 8, compressed, fields.data(), uncompressed);
  if (got != uncompressed) {
    throw FormatError(path.string() + ": PCD binary_compressed data is corrupt (its LZF stream " +
                      (got == 0 ? std::string("does not decompress into ")
                                : "gives " + std::to_string(got) + " of ") +
                      "the " + std::to_string(uncompressed) + " bytes it declares)");
  }
  return decode_points(fields.data(), l, c, block_place);
}

}  // namespace

PcdPoints read_pcd_points(const std::filesystem::path& path) {
  require_readable(path);
  const PcdLayout l = read_pcd_layout(path);
  validate_pcd_sizes(l, path);
  const PcdColumns columns = pcd_columns(l, path);  // fields checked before any data is read
  PcdPoints out;
  out.float32_coordinates = l.sizes[columns.field[0]] == 4 || l.sizes[columns.field[1]] == 4 ||
                            l.sizes[columns.field[2]] == 4;
  if (l.points == 0) return out;
  const std::string bytes = read_file_bytes(path);
  if (l.data == "ascii") {
    out.cloud = read_ascii_pcd(bytes, l, columns, path);
  } else if (l.data == "binary") {
    out.cloud = read_binary_pcd(bytes, l, columns, path);
  } else {
    out.cloud = read_compressed_pcd(bytes, l, columns, path);
  }
  return out;
}

}  // namespace qm3d::pointcloud::detail
