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
  ply::Content content = ply::read(path);
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

// Numbers of a PCD header line (non-numbers count as 0).
std::vector<std::uintmax_t> header_numbers(std::istringstream& words) {
  std::vector<std::uintmax_t> numbers;
  for (std::string w; words >> w;) {
    const bool digits = !w.empty() && w.size() < 19 &&
                        std::all_of(w.begin(), w.end(), [](unsigned char c) { return std::isdigit(c); });
    numbers.push_back(digits ? std::stoull(w) : 0);
  }
  return numbers;
}

// PCL allocates the whole point array from the header's counts, already while reading the
// header: the counts are checked against the file size first, on our own reading of the header
// (binary: exact size; binary_compressed: LZF expands at most ~1:64 here; ASCII: at least two
// characters per value).
void check_pcd_size(const std::filesystem::path& path) {
  const std::uintmax_t file_size = std::filesystem::file_size(path);
  std::ifstream in(path, std::ios::binary);
  std::string line, key, data;
  std::uintmax_t points = 0, offset = 0;
  std::vector<std::uintmax_t> sizes, counts;
  while (data.empty() && offset < (1u << 16) && std::getline(in, line)) {
    offset += line.size() + 1;
    std::istringstream words(line);
    words >> key;
    if (key == "DATA") {
      words >> data;
    } else if (key == "POINTS" || key == "SIZE" || key == "COUNT") {
      const auto numbers = header_numbers(words);
      if (key == "POINTS" && !numbers.empty()) points = numbers[0];
      if (key == "SIZE") sizes = numbers;
      if (key == "COUNT") counts = numbers;
    }
  }
  std::uintmax_t values = 0, point_step = 0;
  for (std::size_t f = 0; f < sizes.size(); ++f) {
    const std::uintmax_t count = f < counts.size() ? std::max<std::uintmax_t>(counts[f], 1) : 1;
    values += count;
    point_step += std::min<std::uintmax_t>(sizes[f], 8) * count;
  }
  const std::uintmax_t body = file_size > offset ? file_size - offset : 0;
  const std::uintmax_t per_point = data == "ascii" ? 2 * std::max<std::uintmax_t>(values, 1)
                                   : data == "binary_compressed" ? 0
                                                                 : std::max<std::uintmax_t>(point_step, 1);
  const bool too_many = per_point > 0 ? points > (body + 64) / per_point
                                      : points * std::max<std::uintmax_t>(point_step, 1) > 64 * (body + 64);
  if (too_many) {
    throw FormatError(path.string() + ": PCD header declares " + std::to_string(points) +
                      " points but the file is too short to hold them");
  }
}

ColoredCloud read_pcd(const std::filesystem::path& path) {
  require_readable(path);
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);  // errors are ours, one line each
  pcl::PCDReader reader;
  check_pcd_size(path);
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

}  // namespace qm3d::pointcloud
