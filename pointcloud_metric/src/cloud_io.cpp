#include "qm3d/pointcloud/cloud_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>
#include <utility>

#include "pcd_io.h"
#include "qm3d/common/error.h"
#include "qm3d/common/ply.h"
#include "qm3d/common/reading.h"

namespace qm3d::pointcloud {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// A PLY without colours gives a cloud with no colours (psnr scores its geometry); the metrics
// that need colours say so with the input's name (require_colours).
CloudData read_ply(const std::filesystem::path& path, ColourScale colour_scale) {
  // ASCII `float` values as float32, as the reference's tinyply reads them (SPEC-PCQM §9.1).
  ply::Content content = ply::read(path, ply::AsciiFloat::kAsDeclared, colour_scale);
  CloudData out{ColoredCloud{std::move(content.positions), std::move(content.colors)},
                std::move(content.warnings), {}};
  out.normals = std::move(content.normals);
  return out;
}

// PCD through qm3d's own reader (pcd_io.h): PCL's I/O library is not linked.
CloudData read_pcd(const std::filesystem::path& path) {
  detail::PcdPoints points = detail::read_pcd_points(path);
  CloudData out;
  out.cloud = std::move(points.cloud);
  for (std::size_t i = 0; i < out.cloud.size(); ++i) {
    for (double v : out.cloud.positions[i]) {
      if (!std::isfinite(v)) {
        throw FormatError(path.string() + ": point " + std::to_string(i) +
                          " has a non-finite coordinate (PCD 'dense false' clouds are not supported)");
      }
    }
  }
  if (points.float32_coordinates) {
    if (auto w = float32_rounding_warning(out.cloud.positions, path.string())) {
      out.warnings.push_back(*w);
    }
  }
  return out;
}

}  // namespace

CloudData read_cloud_data(const std::filesystem::path& path, CloudFormat format,
                          const ReadOptions& options) {
  return format == CloudFormat::kPcd ? read_pcd(path) : read_ply(path, options.colour_scale);
}

void require_colours(const ColoredCloud& cloud, const std::string& name) {
  if (cloud.colors.empty() && !cloud.positions.empty()) {
    const bool pcd = lower(std::filesystem::path(name).extension().string()) == ".pcd";
    throw FormatError(name + ": no vertex colours (PCQM needs one colour per point; expected " +
                      (pcd ? "a packed 'rgb' or 'rgba' PCD field)"
                           : "red/green/blue, r/g/b or diffuse_red/green/blue vertex properties)"));
  }
}

ColoredCloud read_cloud(const std::filesystem::path& path) {
  const std::string ext = lower(path.extension().string());
  if (ext == ".ply") return read_cloud(path, CloudFormat::kPly);
  if (ext == ".pcd") return read_cloud(path, CloudFormat::kPcd);
  throw FormatError(path.string() + ": unknown point-cloud extension '" +
                    path.extension().string() + "' (expected .ply or .pcd)");
}

ColoredCloud read_cloud(const std::filesystem::path& path, CloudFormat format) {
  ColoredCloud cloud = read_cloud_data(path, format).cloud;
  require_colours(cloud, path.string());
  return cloud;
}

}  // namespace qm3d::pointcloud
