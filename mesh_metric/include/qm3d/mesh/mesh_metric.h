// Types shared by the mesh metrics (CMDM, MSDM2): which direction is computed and what each
// direction produces.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "qm3d/common/features.h"

namespace qm3d::mesh {

/// Which mesh's vertices are iterated ("first") and matched on the other ("second").
enum class Direction {
  kSymmetric,  ///< mean of both directions
  kDistToRef,  ///< distorted vertices matched on the reference (MEPP2's "1_2", its tests)
  kRefToDist,  ///< reference vertices matched on the distorted mesh
};

/// The result of one direction.
struct DirectionResult {
  double score = 0;          ///< the metric's pooled score for this direction
  FeatureVector features{};  ///< f1..f8, each averaged over vertices and scales
  double bbox_max_side = 0;  ///< BB: longest bounding-box side of the first mesh
  /// Local distortion of each vertex of the first mesh (averaged over scales), in its input
  /// order; empty when per-vertex output was not requested.
  std::vector<double> local_distortion;
};

struct MeshMetricResult {
  double score = 0;  ///< the requested direction's score, or the mean of both
  std::optional<DirectionResult> dist_to_ref;  ///< iterates the distorted mesh
  std::optional<DirectionResult> ref_to_dist;  ///< iterates the reference mesh
  std::vector<std::string> warnings;  ///< repairs made to the meshes (non-manifold, ...)
};

}  // namespace qm3d::mesh
