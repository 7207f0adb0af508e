// A mesh's samples on a regular grid, as MPEG mmetric makes them (`mm sample --mode grid`; the
// sampler: mesh/grid_sampling.h). Here so that the registry can hand the mesh module's sampler
// to the point-cloud metrics (qm3d psnr on two meshes).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "qm3d/common/types.h"

namespace qm3d {

using Float3 = std::array<float, 3>;

/// An axis-aligned box in float32, as mmetric's --minPos / --maxPos.
struct FloatBox {
  Float3 min{0, 0, 0};
  Float3 max{0, 0, 0};
};

/// The float32 box of a mesh's vertices (mmetric's Geometry::computeBBox: fmin / fmax of the
/// float32 coordinates).
FloatBox vertex_box(const std::vector<Vec3>& positions);
FloatBox vertex_box(const std::vector<Float3>& positions);
/// The union of two boxes (the CTC's shared box of a pair).
FloatBox union_box(const FloatBox& a, const FloatBox& b);

/// A warning for `name` when its box [min, max] lies so far from the origin that float32 (the
/// arithmetic of `tool`: pc_error, mmetric, its renderer) rounds its coordinates by more than
/// 1/8 of `spacing` (described as `spacing_name`; the rule of the readers' float32_rounding_warning, qm3d/common/reading.h),
/// naming the cause and the remedy (move the content near the origin); empty when it does not.
std::string float32_precision_warning(const Vec3& min, const Vec3& max, double spacing,
                                      const std::string& spacing_name, const std::string& name,
                                      const std::string& tool);

struct GridSamplingOptions {
  /// Grid nodes along the box's longest side (mmetric's --gridSize; the CTC uses 1024).
  int grid_size = 1024;
  /// The box the grid spans; unset = the mesh's own vertex box.
  std::optional<FloatBox> box;
  /// Rays along all three axes instead of the normal's main axis only (mmetric without
  /// --useNormal).
  bool all_axes = false;
  /// Texture lookups bilinear (mmetric --bilinear) instead of nearest.
  bool bilinear = false;
  /// OpenMP threads (0 = default); the samples are the same for any count.
  int threads = 0;
};

/// A mesh's grid samples, as mmetric writes them.
struct GridSamples {
  std::vector<Float3> positions;
  std::vector<Float3> normals;                      ///< one per sample: its face's normal
  std::vector<std::array<std::uint8_t, 3>> colours;  ///< one per sample, or empty (no colours)
  FloatBox box;        ///< the box the grid spans
  float step = 0;      ///< the grid step
  std::size_t degenerate_faces = 0;    ///< faces skipped (area below DBL_EPSILON)
  std::size_t duplicate_samples = 0;   ///< samples dropped as equal to an earlier one
  /// Faces with the same corners as an earlier face (sampled once: mmetric drops every sample
  /// of a repeat as a duplicate, counted in duplicate_samples).
  std::size_t repeated_faces = 0;
  /// Faces skipped, mesh vertices outside the given box.
  std::vector<std::string> warnings;
};

}  // namespace qm3d
