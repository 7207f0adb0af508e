// MSDM2, the geometry-only Mesh Structural Distortion Measure (Lavoue, "A Multiscale Metric for
// 3D Mesh Visual Quality Assessment", Computer Graphics Forum 2011), computed as MEPP2's msdm2.h
// does (SPEC-CMDM 2). It shares CMDM's projection, neighbourhood and curvature machinery.
//
// Example:
//   const auto r = qm3d::mesh::compute_msdm2(ref, dist);   // r.score: MEPP2's example_msdm2
#pragma once

#include "qm3d/common/result.h"
#include "qm3d/common/types.h"

namespace qm3d::mesh {

/// MEPP2's example computes distorted -> reference only.
inline constexpr Direction kMsdm2DefaultDirection = Direction::kDistToRef;

/// The run options (a model does not apply: std::invalid_argument) plus MSDM2's own.
struct Msdm2Options : RunOptions {
  /// Number of scales; scale l uses curvature radius (0.002 + 0.001 l) BB and neighbourhood
  /// radius 5x that (MEPP2's example uses 3).
  int scales = 3;
};

/// MSDM2 between a reference and a distorted mesh (colours, if any, are ignored). Per direction:
/// local distortion LD(v) = mean over scales of (f1 + f2 + 0.5 f3) / 2.5, score =
/// (mean LD^3)^(1/3); `features` holds f1..f3 averaged over vertices and scales, `per_element`
/// LD of each vertex of the iterated mesh.
/// Throws like compute_cmdm. Deterministic for any thread count.
MetricResult compute_msdm2(const ColoredMesh& reference, const ColoredMesh& distorted,
                               const Msdm2Options& options = {});

}  // namespace qm3d::mesh
