#include "qm3d/pointcloud/cloud_io.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <sstream>
#include <vector>

#include "qm3d/common/error.h"
#include "qm3d/common/ply.h"

namespace qm3d::pointcloud {
namespace {

/// An 8-bit channel as MEPP-team/PCQM converts it (`RGBtoXYZ`: `_R / 255.0`).
constexpr double kChannelMax = 255.0;

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

FormatError no_colours(const std::filesystem::path& path, const std::string& expected) {
  return FormatError(path.string() + ": no vertex colours (PCQM needs one colour per point; " +
                     "expected " + expected + ")");
}

ColoredCloud read_ply(const std::filesystem::path& path) {
  // ASCII `float` values as float32, as the reference's tinyply reads them (SPEC-PCQM §9.1).
  ply::Content content = ply::read(path, ply::AsciiFloat::kAsDeclared);
  if (content.colors.empty()) {
    throw no_colours(path, "red/green/blue, r/g/b or diffuse_red/green/blue vertex properties");
  }
  return ColoredCloud{std::move(content.positions), std::move(content.colors)};
}

void require_readable(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InputError(path.string() + ": not found or not a regular file");
  }
  std::ifstream probe(path, std::ios::binary);
  if (!probe) throw InputError(path.string() + ": cannot be opened for reading");
}

const pcl::PCLPointField* find_field(const pcl::PCLPointCloud2& cloud, const std::string& name) {
  for (const auto& f : cloud.fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

// Reads one scalar coordinate (float or double) of point i.
double coordinate(const pcl::PCLPointCloud2& cloud, const pcl::PCLPointField& field,
                  std::size_t i) {
  const std::uint8_t* at = cloud.data.data() + i * cloud.point_step + field.offset;
  if (field.datatype == pcl::PCLPointField::FLOAT64) {
    double v;
    std::memcpy(&v, at, sizeof v);
    return v;
  }
  float v;
  std::memcpy(&v, at, sizeof v);
  return v;
}

// A packed rgb / rgba field holds 0x(AA)RRGGBB in its 4 bytes, whether declared F or U.
Rgb packed_colour(const pcl::PCLPointCloud2& cloud, const pcl::PCLPointField& field,
                  std::size_t i) {
  std::uint32_t v;
  std::memcpy(&v, cloud.data.data() + i * cloud.point_step + field.offset, sizeof v);
  return Rgb{((v >> 16) & 0xffu) / kChannelMax, ((v >> 8) & 0xffu) / kChannelMax,
             (v & 0xffu) / kChannelMax};
}

const pcl::PCLPointField& coordinate_field(const pcl::PCLPointCloud2& cloud,
                                           const std::filesystem::path& path,
                                           const std::string& name) {
  const pcl::PCLPointField* f = find_field(cloud, name);
  if (f == nullptr) throw FormatError(path.string() + ": PCD has no '" + name + "' field");
  if (f->datatype != pcl::PCLPointField::FLOAT32 && f->datatype != pcl::PCLPointField::FLOAT64) {
    throw FormatError(path.string() + ": PCD field '" + name + "' is not float or double");
  }
  return *f;
}

const pcl::PCLPointField& colour_field(const pcl::PCLPointCloud2& cloud,
                                       const std::filesystem::path& path) {
  const pcl::PCLPointField* f = find_field(cloud, "rgb");
  if (f == nullptr) f = find_field(cloud, "rgba");
  if (f == nullptr) throw no_colours(path, "a packed 'rgb' or 'rgba' PCD field");
  if (f->datatype != pcl::PCLPointField::FLOAT32 && f->datatype != pcl::PCLPointField::UINT32 &&
      f->datatype != pcl::PCLPointField::INT32) {
    throw FormatError(path.string() + ": PCD field '" + f->name +
                      "' is not a packed 4-byte colour");
  }
  return *f;
}

// PCL's PCDReader::read crashes on a file without FIELDS (it only logs "No points to read"), so
// the header is read and checked first.
pcl::PCLPointCloud2 read_pcd_header(const std::filesystem::path& path, pcl::PCDReader& reader) {
  pcl::PCLPointCloud2 header;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = 0, binary = 0;
  unsigned int data_offset = 0;
  int status = -1;
  try {  // PCL throws on some malformed headers (e.g. a field count of 0)
    status = reader.readHeader(path.string(), header, origin, orientation, version, binary,
                               data_offset);
  } catch (const std::exception& e) {
    throw FormatError(path.string() + ": not a valid PCD header (" + e.what() + ")");
  }
  if (status < 0 || header.fields.empty()) {
    throw FormatError(path.string() + ": not a PCD file (no valid header with FIELDS)");
  }
  return header;
}

// A PCD header as the PCD v0.7 format defines it, read strictly by us before PCL sees the file:
// PCL's own header reader throws, corrupts memory or allocates from the counts on malformed
// headers (found by fuzz_pcd).
struct PcdLayout {
  std::vector<std::string> fields;
  std::vector<std::uintmax_t> sizes, counts;
  std::vector<std::string> types;
  std::uintmax_t width = 0, height = 0, points = 0, header_bytes = 0;
  std::string data;
};

std::uintmax_t header_count(const std::string& w, const std::filesystem::path& path,
                            const std::string& key) {
  const bool digits = !w.empty() && w.size() < 12 &&
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
  if (key == "FIELDS") l.fields = words;
  else if (key == "SIZE") l.sizes = counts();
  else if (key == "TYPE") l.types = words;
  else if (key == "COUNT") l.counts = counts();
  else if (key == "WIDTH" && words.size() == 1) l.width = header_count(words[0], path, key);
  else if (key == "HEIGHT" && words.size() == 1) l.height = header_count(words[0], path, key);
  else if (key == "POINTS" && words.size() == 1) l.points = header_count(words[0], path, key);
  else if (key == "DATA" && words.size() == 1) l.data = words[0];
  else throw FormatError(path.string() + ": not a PCD file (unexpected header line '" + key + "')");
}

void check_layout(const PcdLayout& l, const std::filesystem::path& path) {
  const auto fail = [&](const std::string& what) {
    throw FormatError(path.string() + ": PCD header: " + what);
  };
  const std::size_t n = l.fields.size();
  if (n == 0 || n > 256) fail("FIELDS missing or too many");
  if (l.sizes.size() != n || l.types.size() != n) fail("SIZE and TYPE must have one entry per field");
  if (!l.counts.empty() && l.counts.size() != n) fail("COUNT must have one entry per field");
  for (std::size_t f = 0; f < n; ++f) {
    const auto size = l.sizes[f];
    const bool valid_type = l.types[f] == "I" || l.types[f] == "U" ||
                            (l.types[f] == "F" && (size == 4 || size == 8));
    if (!(size == 1 || size == 2 || size == 4 || size == 8) || !valid_type) {
      fail("field '" + l.fields[f] + "' has SIZE " + std::to_string(size) + " and TYPE " + l.types[f]);
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

// PCL allocates the whole point array from the header's counts: refuse counts the file cannot
// hold (binary: exact size; binary_compressed: LZF expands at most ~1:64 here; ASCII: at least
// two characters per value).
void validate_pcd_header(const std::filesystem::path& path) {
  const PcdLayout l = read_pcd_layout(path);
  std::uintmax_t values = 0, point_step = 0;
  for (std::size_t f = 0; f < l.fields.size(); ++f) {
    const std::uintmax_t count = l.counts.empty() ? 1 : l.counts[f];
    values += count;
    point_step += l.sizes[f] * count;
  }
  const std::uintmax_t file_size = std::filesystem::file_size(path);
  const std::uintmax_t body = file_size > l.header_bytes ? file_size - l.header_bytes : 0;
  const std::uintmax_t needed = l.data == "ascii"    ? l.points * 2 * values
                                : l.data == "binary" ? l.points * point_step
                                                     : l.points * point_step / 64;
  if (needed > body + 64) {
    throw FormatError(path.string() + ": PCD header declares " + std::to_string(l.points) +
                      " points but the file is too short to hold them");
  }
}

ColoredCloud read_pcd(const std::filesystem::path& path) {
  require_readable(path);
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);  // errors are ours, one line each
  pcl::PCDReader reader;
  validate_pcd_header(path);
  pcl::PCLPointCloud2 cloud = read_pcd_header(path, reader);
  // Check the fields on the header before reading any data.
  coordinate_field(cloud, path, "x");
  coordinate_field(cloud, path, "y");
  coordinate_field(cloud, path, "z");
  colour_field(cloud, path);
  if (std::size_t(cloud.width) * cloud.height == 0) return ColoredCloud{};
  int status = -1;
  try {
    status = reader.read(path.string(), cloud);
  } catch (const std::exception& e) {
    throw FormatError(path.string() + ": PCD data cannot be read (" + e.what() + ")");
  }
  if (status < 0) {
    throw FormatError(path.string() + ": PCD data cannot be read (truncated or malformed)");
  }
  const std::size_t n = std::size_t(cloud.width) * cloud.height;
  if (cloud.data.size() < n * cloud.point_step) {
    throw FormatError(path.string() + ": PCD data shorter than its header declares");
  }
  const pcl::PCLPointField* xyz[3] = {&coordinate_field(cloud, path, "x"),
                                      &coordinate_field(cloud, path, "y"),
                                      &coordinate_field(cloud, path, "z")};
  const pcl::PCLPointField& rgb = colour_field(cloud, path);
  // A malformed header (SIZE/COUNT inconsistent with TYPE) can put a field beyond the point
  // record: found by fuzz_pcd as a heap overflow.
  for (const pcl::PCLPointField* f : {xyz[0], xyz[1], xyz[2], &rgb}) {
    const std::size_t bytes = f->datatype == pcl::PCLPointField::FLOAT64 ? 8 : 4;
    if (std::size_t(f->offset) + bytes > cloud.point_step) {
      throw FormatError(path.string() + ": PCD field '" + f->name +
                        "' does not fit in its point record (SIZE/COUNT/TYPE disagree)");
    }
  }
  ColoredCloud out;
  out.positions.resize(n);
  out.colors.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) {
      out.positions[i][a] = coordinate(cloud, *xyz[a], i);
      if (!std::isfinite(out.positions[i][a])) {
        throw FormatError(path.string() + ": point " + std::to_string(i) +
                          " has a non-finite coordinate (PCD 'dense false' clouds are not supported)");
      }
    }
    out.colors[i] = packed_colour(cloud, rgb, i);
  }
  return out;
}

}  // namespace

ColoredCloud read_cloud(const std::filesystem::path& path) {
  const std::string ext = lower(path.extension().string());
  if (ext == ".ply") return read_ply(path);
  if (ext == ".pcd") return read_pcd(path);
  throw FormatError(path.string() + ": unknown point-cloud extension '" +
                    path.extension().string() + "' (expected .ply or .pcd)");
}

ColoredCloud read_cloud(const std::filesystem::path& path, CloudFormat format) {
  return format == CloudFormat::kPcd ? read_pcd(path) : read_ply(path);
}

}  // namespace qm3d::pointcloud
