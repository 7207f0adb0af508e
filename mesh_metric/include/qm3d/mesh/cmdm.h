// CMDM, the Color Mesh Distortion Measure (Nehme, Dupont, Farrugia, Le Callet, Lavoue, "Visual
// Quality of 3D Meshes With Diffuse Colors in Virtual Reality: Subjective and Objective
// Evaluation", IEEE TVCG 2021), computed exactly as MEPP2's CMDM filter does (SPEC-CMDM).
//
// Example:
//   const auto ref = qm3d::mesh::read_mesh("ref.obj").mesh;
//   const auto dist = qm3d::mesh::read_mesh("dist.obj").mesh;
//   const qm3d::mesh::CmdmResult r = qm3d::mesh::compute_cmdm(ref, dist);
//   // r.score: symmetric CMDM; r.dist_to_ref->score: what MEPP2's test_cmdm checks.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "qm3d/common/features.h"
#include "qm3d/common/pooling.h"
#include "qm3d/common/types.h"

namespace qm3d::mesh {

/// Which mesh's vertices are iterated.
enum class CmdmDirection {
  kSymmetric,  ///< mean of both directions (the paper's eq. 1.12; MEPP2's example)
  kDistToRef,  ///< distorted vertices projected on the reference (MEPP2 "1_2", test_cmdm)
  kRefToDist,  ///< reference vertices projected on the distorted mesh
};

struct CmdmOptions {
  CmdmDirection direction = CmdmDirection::kSymmetric;
  /// Number of scales; scale l uses curvature radius (0.001 + 0.0005 l) BB and neighbourhood
  /// radius 3x that (MEPP2 hard-codes 3).
  int scales = 3;
  /// Weights of f1..f8 (default: the published 0.091 f2 + 0.22 f5 + 0.032 f6 + 0.656 f7).
  LinearModel model = cmdm_model();
  /// LAB2000HL table directory; empty = resolve_data_dir().
  std::filesystem::path data_dir;
  /// Keep the per-vertex local distortion in the result.
  bool per_vertex = true;
};

/// The result of one direction (the mesh whose vertices are iterated is "first").
struct CmdmDirectionResult {
  double score = 0;            ///< model applied to `features` (= mean local distortion)
  FeatureVector features{};    ///< f1..f8, each averaged over vertices and scales
  double bbox_max_side = 0;    ///< BB: longest bounding-box side of the first mesh
  /// Local distortion of each vertex of the first mesh, in its input order (empty when
  /// CmdmOptions::per_vertex is false).
  std::vector<double> local_distortion;
};

struct CmdmResult {
  double score = 0;  ///< the requested direction's score, or the mean of both
  std::optional<CmdmDirectionResult> dist_to_ref;  ///< iterates the distorted mesh
  std::optional<CmdmDirectionResult> ref_to_dist;  ///< iterates the reference mesh
  std::vector<std::string> warnings;  ///< repairs made to the meshes (non-manifold, ...)
};

/// Computes CMDM between a reference and a distorted mesh. Throws NumericError for meshes the
/// metric cannot handle (zero-size bounding box), FormatError for invalid faces, InputError /
/// FormatError for a missing or malformed LAB2000HL table, std::invalid_argument for bad options.
/// Deterministic: any thread count gives bit-identical results.
CmdmResult compute_cmdm(const ColoredMesh& reference, const ColoredMesh& distorted,
                        const CmdmOptions& options = {});

}  // namespace qm3d::mesh
