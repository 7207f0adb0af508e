#include "qm3d/pointcloud/cloud_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

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

bool finite_point(const Vec3& p) {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

// PCL's rule for the points of an organised ("dense false") cloud with a NaN or infinite
// coordinate (pcl::removeNaNFromPointCloud, filters/impl/filter.hpp in PCL 1.13: a point is
// kept when x, y and z are all finite): they are invalid measurements (depth-camera pixels
// without a return) and are dropped, in file order, with one warning giving their count. A cloud
// with no valid point is an error.
void drop_invalid_points(ColoredCloud& cloud, std::vector<std::string>& warnings,
                         const std::filesystem::path& path) {
  const std::size_t n = cloud.size();
  std::size_t kept = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!finite_point(cloud.positions[i])) continue;
    cloud.positions[kept] = cloud.positions[i];
    if (!cloud.colors.empty()) cloud.colors[kept] = cloud.colors[i];
    ++kept;
  }
  if (kept == n) return;
  if (kept == 0) {
    throw FormatError(path.string() + ": all " + std::to_string(n) +
                      " points have a NaN or infinite coordinate (no valid point)");
  }
  cloud.positions.resize(kept);
  if (!cloud.colors.empty()) cloud.colors.resize(kept);
  warnings.push_back(path.string() + ": " + std::to_string(n - kept) + " of " + std::to_string(n) +
                     " points have a NaN or infinite coordinate (invalid measurements of an "
                     "organised cloud): dropped, as pcl::removeNaNFromPointCloud does");
}

// PCD through qm3d's own reader (pcd_io.h): PCL's I/O library is not linked.
CloudData read_pcd(const std::filesystem::path& path) {
  detail::PcdPoints points = detail::read_pcd_points(path);
  CloudData out;
  out.cloud = std::move(points.cloud);
  drop_invalid_points(out.cloud, out.warnings, path);
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
