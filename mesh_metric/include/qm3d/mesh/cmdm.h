// CMDM, the Color Mesh Distortion Measure (Nehme, Dupont, Farrugia, Le Callet, Lavoue, "Visual
// Quality of 3D Meshes With Diffuse Colors in Virtual Reality: Subjective and Objective
// Evaluation", IEEE TVCG 2021), computed exactly as MEPP2's CMDM filter does (SPEC-CMDM).
//
// Example:
//   const auto ref = qm3d::mesh::read_mesh("ref.obj").mesh;
//   const auto dist = qm3d::mesh::read_mesh("dist.obj").mesh;
//   const qm3d::mesh::MeshMetricResult r = qm3d::mesh::compute_cmdm(ref, dist);
//   // r.score: symmetric CMDM; r.dist_to_ref->score: what MEPP2's test_cmdm checks.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "qm3d/common/features.h"
#include "qm3d/common/pooling.h"
#include "qm3d/common/progress.h"
#include "qm3d/common/types.h"
#include "qm3d/mesh/mesh_metric.h"

namespace qm3d::mesh {

struct CmdmOptions {
  Direction direction = Direction::kSymmetric;
  /// Number of scales; scale l uses curvature radius (0.001 + 0.0005 l) BB and neighbourhood
  /// radius 3x that (MEPP2 hard-codes 3).
  int scales = 3;
  /// Weights of f1..f8 (default: the published 0.091 f2 + 0.22 f5 + 0.032 f6 + 0.656 f7).
  LinearModel model = cmdm_model();
  /// LAB2000HL table directory; empty = resolve_data_dir().
  std::filesystem::path data_dir;
  /// Keep the per-vertex local distortion in the result.
  bool per_vertex = true;
  /// OpenMP threads for every parallel part (0 = the calling thread's OpenMP default). The
  /// result does not depend on it (bit-identical for any count).
  int threads = 0;
  /// Optional: told each stage as it starts (progress.h); the result does not depend on it.
  ProgressCallback progress;
};

/// Computes CMDM between a reference and a distorted mesh. Throws NumericError for meshes the
/// metric cannot handle (zero-size bounding box), FormatError for invalid faces, InputError /
/// FormatError for a missing or malformed LAB2000HL table, std::invalid_argument for bad options.
/// Deterministic: any thread count gives bit-identical results.
MeshMetricResult compute_cmdm(const ColoredMesh& reference, const ColoredMesh& distorted,
                        const CmdmOptions& options = {});

}  // namespace qm3d::mesh
