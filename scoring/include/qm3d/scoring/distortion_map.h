// Writing per-vertex / per-point distortion as a PLY file to open in MeshLab or CloudCompare.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "qm3d/common/types.h"

namespace qm3d::scoring {

/// Writes a binary PLY with the positions, the float properties `distortion`, `quality` (MeshLab's
/// vertex quality) and `scalar_distortion` (a CloudCompare scalar field), all holding `values`, and
/// a heat-map colour (blue = lowest value of the object, red = highest), plus the triangles (empty
/// for a point cloud). Written atomically: never a partial file.
void write_distortion_map(const std::filesystem::path& path, const std::vector<Vec3>& positions,
                          const std::vector<Triangle>& triangles, const std::vector<double>& values,
                          const std::vector<std::pair<std::string, std::vector<double>>>& more = {});

/// Heat-map colour of t in [0, 1]: blue, cyan, green, yellow, red.
std::array<std::uint8_t, 3> heat_color(double t);

}  // namespace qm3d::scoring
