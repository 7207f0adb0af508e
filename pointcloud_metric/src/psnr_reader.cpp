#include "psnr_reader.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>

#include "qm3d/common/error.h"
#include "qm3d/common/ply.h"
#include "qm3d/common/reading.h"

namespace qm3d::pointcloud::detail {
namespace {

/// The header is looked for in the file's first bytes (a longer header: the general reader).
constexpr std::size_t kHeaderBytes = 1 << 16;
/// Points decoded per block read.
constexpr std::size_t kBlockPoints = 1 << 16;

std::size_t scalar_bytes(ply::ScalarType t) {
  switch (t) {
    case ply::ScalarType::kInt8:
    case ply::ScalarType::kUint8:
      return 1;
    case ply::ScalarType::kInt16:
    case ply::ScalarType::kUint16:
      return 2;
    case ply::ScalarType::kInt32:
    case ply::ScalarType::kUint32:
    case ply::ScalarType::kFloat32:
      return 4;
    case ply::ScalarType::kFloat64:
      break;
  }
  return 8;
}

bool little_endian_host() {
  const std::uint16_t one = 1;
  std::uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

/// Byte offsets of the properties read in one vertex record (-1: absent).
struct Layout {
  std::size_t stride = 0;
  long xyz[3] = {-1, -1, -1};
  long rgb[3] = {-1, -1, -1};
  long normal[3] = {-1, -1, -1};
};

// The offsets of `names` when all three are there with type `type`; false when they are there
// with another type or only some of them are (the general reader then decides).
bool find_three(const ply::Element& e, const std::vector<long>& offsets, const char* const* names,
                ply::ScalarType type, long* out) {
  int found = 0;
  for (int c = 0; c < 3; ++c) {
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      if (e.properties[k].name != names[c]) continue;
      if (e.properties[k].type != type) return false;
      out[c] = offsets[k];
      ++found;
      break;
    }
  }
  if (found != 0 && found != 3) return false;
  if (found == 0) out[0] = out[1] = out[2] = -1;
  return true;
}

// The layout of a vertex-only binary little-endian PLY of float x, y, z (+ uchar red, green,
// blue, + float nx, ny, nz), or nullopt.
std::optional<Layout> simple_layout(const ply::Header& h) {
  if (h.format != ply::Format::kBinaryLittleEndian || h.elements.size() != 1) return std::nullopt;
  const ply::Element& e = h.elements[0];
  if (e.name != "vertex" || e.count == 0) return std::nullopt;
  Layout l;
  std::vector<long> offsets;
  for (const ply::Property& p : e.properties) {
    if (p.is_list) return std::nullopt;
    offsets.push_back(static_cast<long>(l.stride));
    l.stride += scalar_bytes(p.type);
  }
  static const char* const kXyz[3] = {"x", "y", "z"};
  static const char* const kRgb[3] = {"red", "green", "blue"};
  static const char* const kNormal[3] = {"nx", "ny", "nz"};
  // Other colour names (r, g, b; diffuse_*) are the general reader's to pick.
  static const char* const kOtherColours[6] = {
      "r", "g", "b", "diffuse_red", "diffuse_green", "diffuse_blue"};
  for (const ply::Property& p : e.properties) {
    for (const char* other : kOtherColours) {
      if (p.name == other) return std::nullopt;
    }
  }
  if (!find_three(e, offsets, kXyz, ply::ScalarType::kFloat32, l.xyz) || l.xyz[0] < 0 ||
      !find_three(e, offsets, kRgb, ply::ScalarType::kUint8, l.rgb) ||
      !find_three(e, offsets, kNormal, ply::ScalarType::kFloat32, l.normal)) {
    return std::nullopt;
  }
  return l;
}

// One vertex record into point i; false when a coordinate is not finite (the general reader
// refuses the file, naming the vertex).
bool decode(const char* record, const Layout& l, std::size_t i, FloatCloud& out) {
  for (int c = 0; c < 3; ++c) std::memcpy(&out.positions[i][c], record + l.xyz[c], sizeof(float));
  if (l.rgb[0] >= 0) {
    for (int c = 0; c < 3; ++c) {
      out.colours[i][c] = static_cast<std::uint8_t>(record[l.rgb[c]]);
    }
  }
  if (l.normal[0] >= 0) {
    for (int c = 0; c < 3; ++c) {
      std::memcpy(&out.normals[i][c], record + l.normal[c], sizeof(float));
    }
  }
  const Point3f& p = out.positions[i];
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

}  // namespace

std::optional<FloatCloudFile> read_float_ply(const std::filesystem::path& path) {
  if (!little_endian_host()) return std::nullopt;
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec || !std::filesystem::is_regular_file(path, ec)) return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::string head(kHeaderBytes, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  if (head.find("end_header") == std::string::npos) return std::nullopt;
  std::optional<Layout> layout;
  ply::Header h;
  try {
    h = ply::parse_header(head, path.string(), size);
    layout = simple_layout(h);
  } catch (const Error&) {
    return std::nullopt;  // the general reader says what is wrong
  }
  if (!layout) return std::nullopt;
  const std::uint64_t n = h.elements[0].count;
  if (h.data_offset + n * layout->stride != size) return std::nullopt;

  FloatCloudFile out;
  out.cloud.positions.resize(n);
  if (layout->rgb[0] >= 0) out.cloud.colours.resize(n);
  if (layout->normal[0] >= 0) out.cloud.normals.resize(n);
  in.clear();
  in.seekg(static_cast<std::streamoff>(h.data_offset));
  std::string block(kBlockPoints * layout->stride, '\0');
  for (std::uint64_t first = 0; first < n; first += kBlockPoints) {
    const std::size_t count =
        static_cast<std::size_t>(std::min<std::uint64_t>(kBlockPoints, n - first));
    in.read(block.data(), static_cast<std::streamsize>(count * layout->stride));
    if (static_cast<std::size_t>(in.gcount()) != count * layout->stride) {
      throw InputError(path.string() + ": read failed (the file changed while read?)");
    }
    for (std::size_t k = 0; k < count; ++k) {
      if (!decode(block.data() + k * layout->stride, *layout, first + k, out.cloud)) {
        return std::nullopt;
      }
    }
  }
  // The general reader's warning for float32 coordinates.
  if (auto w = float32_rounding_warning(out.cloud.positions, path.string())) {
    out.warnings.push_back(*w);
  }
  return out;
}

}  // namespace qm3d::pointcloud::detail
