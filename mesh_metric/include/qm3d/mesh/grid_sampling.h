// MPEG mmetric's grid sampling of a mesh (`mm sample --mode grid`, MPEGGroup/mpeg-pcc-mmetric
// 1.1.7 @ 5faa660, source/lib/source/mmSample.cpp, Sample::meshToPcGrid): the mesh-coding CTC
// (V-Mesh / V-DMC) samples both meshes of a pair this way on one box, then compares the two
// clouds with pc_error's metric (qm3d psnr).
//
// The rules, each as mmetric has them (everything in float32, as its glm::vec3):
// - Box: the given one, or the mesh's own vertex box (fmin / fmax of the float32 vertices). The
//   step is the same on all axes: (longest side of the box) * (1 / (G - 1)).
// - Per triangle, in file order: skipped when its area 0.5 |(v2 - v1) x (v3 - v1)| is below
//   DBL_EPSILON; its normal is normalize((v2 - v1) x (v3 - v1)). The grid nodes of the
//   triangle's box, lmin = floor((tmin - box min) / step), lmax = ceil((tmax - box min) / step),
//   send rays along one axis: the axis of the normal's largest component (ties to the lower
//   axis; mmetric's --useNormal, the CTC's choice), or all three axes in turn (x, y, z) with
//   `all_axes`. The ray from node (i, j) of the two other axes, starting on the plane
//   box min + lmin * step of the ray's axis, hits the triangle by Moller-Trumbore (determinant
//   within 1e-6 of 0: no hit; u, v in [0, 1], u + v <= 1 inclusive); the sample is the hit
//   point with the face normal and the colour interpolated barycentrically (vertex colours in
//   0..255, or the texture at the interpolated UV: nearest texel, or bilinear).
// - A sample equal to an earlier one in position, colour and normal is dropped (mmetric's
//   ModelBuilder); samples keep their first-seen order.
// - Colours are written as 8-bit, rounded (mmetric's PLY writer and its compare's conversion).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "qm3d/common/grid_samples.h"
#include "qm3d/common/types.h"
#include "qm3d/mesh/texture.h"

namespace qm3d::mesh {

/// The most samples one call produces (a mistaken grid size, not a cloud to score).
constexpr std::size_t kMaxGridSamples = 500000000;

/// Samples `mesh` (colours: its vertex colours when `mesh.colors` is not empty, else none).
/// Throws std::invalid_argument for a grid size below 2 or above 1,000,000, NumericError when
/// the box is flat on two axes (no rays) or not finite, the grid gives no samples, or mmetric's
/// float32 arithmetic overflows (coordinates beyond about 1e12), MemoryLimitError (before
/// sampling, with the estimate) when the estimated samples exceed kMaxGridSamples or the memory
/// the process may use. Faces with the same corners as an earlier one are sampled once.
GridSamples sample_grid(const ColoredMesh& mesh, const GridSamplingOptions& options);
/// Samples a textured mesh: colours from its textures at each sample's UV.
GridSamples sample_grid(const TexturedMesh& mesh, const GridSamplingOptions& options);

}  // namespace qm3d::mesh
