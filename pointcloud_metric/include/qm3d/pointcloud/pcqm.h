// PCQM, the full-reference quality metric for coloured point clouds of Meynet, Nehme, Digne and
// Lavoue ("PCQM: A Full-Reference Quality Metric for Colored 3D Point Clouds", QoMEX 2020), as
// MEPP-team/PCQM main.cpp computes it (docs SPEC-PCQM.md): per point of the reference, a quadric
// fit gives its correspondence on the distorted cloud and both clouds' mean curvatures; eight
// local curvature and LAB2000HL colour features over a Gaussian-weighted neighbourhood are
// averaged, and PCQM = 0.0057 F3 + 0.9771 F4 + 0.0172 F6 (0 = identical, about 1 = worst).
//
// Example:
//   auto ref = qm3d::pointcloud::read_cloud("ref.ply");
//   auto dist = qm3d::pointcloud::read_cloud("dist.ply");
//   qm3d::pointcloud::PcqmResult r = qm3d::pointcloud::compute_pcqm(ref, dist);
//   std::cout << r.score << "\n";
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "qm3d/common/features.h"
#include "qm3d/common/pooling.h"
#include "qm3d/common/progress.h"
#include "qm3d/common/types.h"

namespace qm3d::pointcloud {

/// How the bounding-box size maxDim (which scales the radii and the curvatures) is measured on
/// the iterated cloud.
enum class BboxMode {
  /// max over axes of |min| + |max|, with max starting at DBL_MIN (+2.2e-308): the reference
  /// implementation's value, which depends on where the cloud sits (SPEC-PCQM 1.3). Needed to
  /// reproduce the reference scores.
  kReference,
  /// The true longest side max over axes of (max - min): translation invariant.
  kExtent,
};

struct PcqmOptions {
  /// Curvature radius as a fraction of maxDim: r = radius_rel * maxDim (reference `-r`).
  double radius_rel = 0.004;
  /// k of the kNN used for the correspondence quadric (reference `-knn`); min(knn, #points) is
  /// used on small clouds.
  int knn = 20;
  /// The statistics neighbourhood radius is radius_factor * r, the Gaussian sigma half of it
  /// (reference `-rx`).
  double radius_factor = 2.0;
  BboxMode bbox = BboxMode::kReference;
  /// Also compute distorted -> reference (roles swapped) and report the mean of both scores.
  /// The reference implementation has no such mode: false reproduces it.
  bool symmetric = false;
  /// Directory of the LAB2000HL tables; empty = qm3d::resolve_data_dir().
  std::filesystem::path data_dir;
  /// OpenMP threads; 0 = the OpenMP default. The result does not depend on it (bit-identical).
  int threads = 0;
  /// Fill PcqmDirection::per_point.
  bool per_point = true;
  /// Weights of F1..F8 (default: the published 0.0057 F3 + 0.9771 F4 + 0.0172 F6).
  LinearModel model = pcqm_model();
  /// Optional: told each stage as it starts (progress.h); the result does not depend on it.
  ProgressCallback progress;
};

/// One direction: the points of `reference` iterated, their correspondences found on the other
/// cloud.
struct PcqmDirection {
  double score = 0;          ///< 0.0057 F3 + 0.9771 F4 + 0.0172 F6
  FeatureVector features{};  ///< F1..F8: the means over the iterated cloud's points
  double bbox_max_side = 0;  ///< maxDim used for the radii and the curvature scaling
  /// Local distortion of each point of the iterated cloud (in its input order):
  /// 0.0057 f3 + 0.9771 f4 + 0.0172 f6. Empty when PcqmOptions::per_point is false.
  std::vector<double> per_point;
};

struct PcqmResult {
  double score = 0;           ///< ref_to_dist.score, or the mean of both directions when symmetric
  PcqmDirection ref_to_dist;  ///< the reference's points iterated (the paper's PCQM)
  std::optional<PcqmDirection> dist_to_ref;  ///< set when PcqmOptions::symmetric
  std::vector<std::string> warnings;         ///< e.g. the bounding-box quirk being far off
};

/// Computes PCQM of `distorted` against `reference`.
///
/// @param[in] reference  #R points with colours: the reference R (the reference tool's argv1)
/// @param[in] distorted  #D points with colours: the distorted D (argv2)
/// @param[in] options    see PcqmOptions
/// @throws std::invalid_argument  an option out of range (radius_rel <= 0, knn < 1, ...)
/// @throws NumericError  an empty cloud, colours missing or not one per point, non-finite
///                       coordinates, or a zero-size bounding box (the message names the cloud)
/// @throws InputError / FormatError  the LAB2000HL tables cannot be read
///
/// \bug With BboxMode::kReference the score changes when both clouds are translated; a warning
///      is added when the quirk differs from the true longest side by more than 1%.
PcqmResult compute_pcqm(const ColoredCloud& reference, const ColoredCloud& distorted,
                        const PcqmOptions& options = {});

}  // namespace qm3d::pointcloud
