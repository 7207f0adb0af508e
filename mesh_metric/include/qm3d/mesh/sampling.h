// Area-uniform sampling of a mesh surface into a coloured point cloud, so that one stimulus can
// be scored both as a mesh (CMDM, MSDM2) and as a point cloud (PCQM).
//
// Each sample picks a triangle with probability proportional to its area (binary search in the
// cumulative areas), then a uniform point in it with the square-root trick (Osada et al. 2002,
// "Shape distributions", eq. 1). The random numbers come from one std::mt19937_64 stream seeded
// with `seed` and consumed serially, so a seed gives the same cloud on any thread count and any
// standard library.
#pragma once

#include <cstddef>
#include <cstdint>

#include "qm3d/common/types.h"
#include "qm3d/mesh/texture.h"

namespace qm3d::mesh {

/// How many samples to draw: set exactly one of `points` and `density`.
struct SamplingOptions {
  /// Number of samples (0 = use `density`).
  std::size_t points = 0;
  /// Samples per unit area, in the mesh's units^-2 (0 = use `points`); the count is
  /// round(density * total area).
  double density = 0;
  /// Seed of the random stream.
  std::uint64_t seed = 1;
};

/// The most samples one call draws: a billion points are about 50 GB of cloud and k-d tree; a
/// larger count is a mistaken density, not a cloud anyone can score.
constexpr std::size_t kMaxSamples = 1000000000;

/// Number of samples `options` asks for on a surface of `total_area`. Throws NumericError when
/// both or neither of points / density are set, density is negative or not finite, or the count
/// is zero or above kMaxSamples (the message gives the count the density would give).
std::size_t sample_count(const SamplingOptions& options, double total_area);

/// Samples the surface of `mesh`; colours interpolated barycentrically from the vertex colours.
/// @param[in] mesh  #V positions, #V colours, #F triangles (at least one with positive area)
/// @return #N points and colours
/// Throws NumericError when the mesh has no colours, no area, or the options are invalid.
ColoredCloud sample_surface(const ColoredMesh& mesh, const SamplingOptions& options);

/// Samples a textured mesh: the same points as for `mesh.file.mesh` with the same options, each
/// coloured by the texture at its own UV (not from the vertex colours).
ColoredCloud sample_surface(const TexturedMesh& mesh, const SamplingOptions& options);

}  // namespace qm3d::mesh
