// MSDM2, the geometry-only Mesh Structural Distortion Measure (Lavoue, "A Multiscale Metric for
// 3D Mesh Visual Quality Assessment", Computer Graphics Forum 2011), computed as MEPP2's msdm2.h
// does (SPEC-CMDM 2). It shares CMDM's projection, neighbourhood and curvature machinery.
//
// Example:
//   const auto r = qm3d::mesh::compute_msdm2(ref, dist);   // r.score: MEPP2's example_msdm2
#pragma once

#include "qm3d/common/progress.h"
#include "qm3d/common/types.h"
#include "qm3d/mesh/mesh_metric.h"

namespace qm3d::mesh {

struct Msdm2Options {
  /// MEPP2's example computes distorted -> reference only; kSymmetric averages both.
  Direction direction = Direction::kDistToRef;
  /// Number of scales; scale l uses curvature radius (0.002 + 0.001 l) BB and neighbourhood
  /// radius 5x that (MEPP2's example uses 3).
  int scales = 3;
  /// Keep the per-vertex local distortion in the result.
  bool per_vertex = true;
  /// OpenMP threads for every parallel part (0 = the calling thread's OpenMP default). The
  /// result does not depend on it (bit-identical for any count).
  int threads = 0;
  /// Optional: told each stage as it starts (progress.h); the result does not depend on it.
  ProgressCallback progress;
};

/// MSDM2 between a reference and a distorted mesh (colours, if any, are ignored). Per direction:
/// local distortion LD(v) = mean over scales of (f1 + f2 + 0.5 f3) / 2.5, score =
/// (mean LD^3)^(1/3); `features` holds f1..f3 averaged over vertices and scales.
/// Throws like compute_cmdm. Deterministic for any thread count.
MeshMetricResult compute_msdm2(const ColoredMesh& reference, const ColoredMesh& distorted,
                               const Msdm2Options& options = {});

}  // namespace qm3d::mesh
