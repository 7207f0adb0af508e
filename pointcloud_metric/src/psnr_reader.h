// psnr's own reader of the common cloud file: a binary little-endian PLY whose only element is
// `vertex`, with float x, y, z, optional uchar red, green, blue and optional float nx, ny, nz.
// It reads straight into what pc_error holds (float32 positions and normals, 8-bit colours: 15
// bytes a point instead of the general reader's 48), in blocks, never the whole file at once.
// Every other file (ASCII, big-endian, double or 16-bit values, other colour names, faces or
// other elements, a size that does not match the header, a coordinate that is not finite) is
// left to the general reader, which gives the same values and explains what is wrong with a bad
// file.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "psnr_engine.h"

namespace qm3d::pointcloud::detail {

struct FloatCloudFile {
  FloatCloud cloud;
  std::vector<std::string> warnings;  ///< the general reader's for this file (float32 rounding)
};

/// The file's points, or nullopt when it is not the simple layout above (read it in full then).
std::optional<FloatCloudFile> read_float_ply(const std::filesystem::path& path);

}  // namespace qm3d::pointcloud::detail
