#include "qm3d/scoring/distortion_map.h"

#include <algorithm>
#include <cmath>

#include "qm3d/common/ply.h"

namespace qm3d::scoring {

std::array<std::uint8_t, 3> heat_color(double t) {
  static constexpr double kStops[5][3] = {
      {0, 0, 255}, {0, 255, 255}, {0, 255, 0}, {255, 255, 0}, {255, 0, 0}};
  if (!std::isfinite(t)) t = 0;
  t = std::clamp(t, 0.0, 1.0) * 4.0;
  const int i = std::min(static_cast<int>(t), 3);
  const double u = t - i;
  std::array<std::uint8_t, 3> c{};
  for (int k = 0; k < 3; ++k) {
    c[k] = static_cast<std::uint8_t>(std::lround((1 - u) * kStops[i][k] + u * kStops[i + 1][k]));
  }
  return c;
}

void write_distortion_map(const std::filesystem::path& path, const std::vector<Vec3>& positions,
                          const std::vector<Triangle>& triangles, const std::vector<double>& values,
                          const std::vector<std::pair<std::string, std::vector<double>>>& more) {
  ply::WriteData d;
  d.positions = positions;
  d.double_positions = true;
  d.triangles = triangles;
  // The same values three times: our own name, MeshLab's vertex quality, a CloudCompare scalar
  // field (CloudCompare loads every extra float property; "scalar_" is its own prefix).
  d.scalar_names = {"distortion", "quality", "scalar_distortion"};
  d.scalars.assign(values.begin(), values.end());
  for (const auto& [name, v] : more) d.extra_scalars.emplace_back("scalar_" + name, std::vector<float>(v.begin(), v.end()));
  double lo = 0, hi = 0;
  if (!values.empty()) {
    const auto [mn, mx] = std::minmax_element(values.begin(), values.end());
    lo = *mn;
    hi = *mx;
  }
  d.colors.reserve(values.size());
  for (double v : values) d.colors.push_back(heat_color(hi > lo ? (v - lo) / (hi - lo) : 0.0));
  ply::write(path, d);
}

}  // namespace qm3d::scoring
