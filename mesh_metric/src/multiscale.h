// The multi-scale engine shared by CMDM and MSDM2 (SPEC-CMDM 1.4-1.9 and 2): match each vertex of
// one mesh on the other, estimate curvature at each scale, walk each vertex's neighbourhood and
// accumulate its local features over the scales. The metrics differ only by the parameters in
// MultiscaleDefinition and by how they pool the per-vertex results. Internal.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "curvature.h"
#include "projection.h"
#include "qm3d/common/color.h"
#include "qm3d/common/features.h"
#include "qm3d/common/progress.h"
#include "qm3d/common/result.h"

namespace qm3d::mesh::detail {

/// What distinguishes one multi-scale mesh metric from another.
struct MultiscaleDefinition {
  const char* name;                    ///< "CMDM", "MSDM2" (for messages)
  CurvatureVariant curvature;
  DegenerateEdges degenerate_edges;    ///< curvature next to zero-length edges / zero-area faces
  double first_radius;                 ///< rc at the first scale (fraction of BB)
  double radius_step;                  ///< rc increment per scale
  double neighbourhood_factor;         ///< neighbourhood radius h = factor * rc * BB
  double sigma_divisor;                ///< Gaussian sigma = h / divisor
  HeronAnchor anchor;                  ///< where the interpolation distances are measured from
  bool strict_outward_test;            ///< walk test "> 0" (MSDM2) or ">= 0" (CMDM)
  bool uses_color;                     ///< sample LAB2000HL colours (CMDM)
  FeatureConventions conventions;
};

// The two metrics side by side: everything that differs between them, besides their pooling.

/// MEPP2 process_CMDM_multires (SPEC-CMDM 1.4-1.8): rc = 0.001, +0.0005 per scale; curvature
/// radius rc BB from crossing edges only, with curvature_cmdm.hpp's replacement normals next to
/// collinear faces; neighbourhood h = 3 rc BB, sigma = h / 3; Heron distances from the projected
/// point; ">= 0" walk test; colour; w1 covariances clamped at 0.
inline constexpr MultiscaleDefinition kCmdmDefinition{
    "CMDM", CurvatureVariant::kCmdm, DegenerateEdges::kRepaired, 0.001, 0.0005, 3.0, 3.0,
    HeronAnchor::kProjectedPoint, /*strict_outward_test=*/false, /*uses_color=*/true,
    kCmdmConventions};

/// MEPP2 process_msdm2_multires (SPEC-CMDM 2): rc = 0.002, +0.001 per scale; generic curvature
/// (every edge in the ball); neighbourhood h = 5 rc BB, sigma = h / 2; Heron distances from the
/// distorted vertex itself; "> 0" walk test; no colour; mixed-weight unclamped covariance.
/// Degenerate geometry (SPEC-CMDM §MSDM2-degenerate): the generic curvature code has no special
/// case for it, so a vertex whose curvature ball, at a given scale, takes in a non-border edge of
/// zero length or an edge of a zero-area face (NaN normal) gets a NaN tensor, its eigen-solver
/// fails and its curvature is 0 at that scale.
inline constexpr MultiscaleDefinition kMsdm2Definition{
    "MSDM2", CurvatureVariant::kGeneric, DegenerateEdges::kVoidTensor, 0.002, 0.001, 5.0, 2.0,
    HeronAnchor::kQueryPoint, /*strict_outward_test=*/true, /*uses_color=*/false,
    kMsdm2Conventions};

/// Pools one direction's per-vertex feature sums (over `scales` scales) into `result`.
using DirectionPooling = std::function<void(const std::vector<FeatureVector>& sums, int scales,
                                            DirectionResult& result)>;

struct MultiscaleRun {
  Direction direction = Direction::kSymmetric;
  int scales = 3;
  /// OpenMP threads for every parallel part, concurrent tasks included; 0 = the calling
  /// thread's OpenMP default (omp_get_max_threads()). The result does not depend on it.
  int threads = 0;
  const Lab2000hlTable* colors = nullptr;  ///< required when the definition uses colour
  ProgressCallback progress;               ///< optional: told each stage as it starts
  /// Optional: called once both meshes are prepared (the inputs are not read afterwards).
  std::function<void()> inputs_done;
};

/// Runs a metric on a pair of meshes: prepares both, computes the requested directions, and
/// averages them for the symmetric score.
MetricResult run_multiscale(const ColoredMesh& reference, const ColoredMesh& distorted,
                                const MultiscaleDefinition& definition, const MultiscaleRun& run,
                                const DirectionPooling& pool);

}  // namespace qm3d::mesh::detail
