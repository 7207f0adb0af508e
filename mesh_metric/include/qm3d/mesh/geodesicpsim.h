// GeodesicPSIM: quality of a textured mesh against a reference by geodesic patch similarity
// (Yang, Jung, Xu, Liu, "GeodesicPSIM: Predicting the Quality of Static Mesh with Texture Map via
// Geodesic Patch Similarity", arXiv:2308.04928), equal to its C++ reference
// Qi-Yangsjtu/GeodesicPSIM @ 3e06453 (docs/geodesicpsim.md).
//
// Keypoints are farthest points of the reference's vertices; around each, the 1-ring of the
// nearest vertex of either mesh is shrunk to a tiny common size, and four similarities compare
// the two patches: colour smoothness on the patch graph (pcs), discrete mean curvature (dmc),
// texel colour average (pca) and variance (pcv). Score = their mean, in [0, 1], 1 = identical.
//
// Example:
//   qm3d::mesh::GeodesicPsimOptions o;  o.keypoints = 500;
//   const auto r = qm3d::mesh::compute_geodesicpsim("ref.obj", "dist.obj", o);
//   r.score; r.pcs; r.keypoints[k].flag;
//
// \bug Textures decode with stb: JPEG textures may differ by a level from the reference's
// OpenCV (libjpeg) decode; PNG is bit-exact. One texture image per mesh.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "qm3d/common/metric.h"
#include "qm3d/common/result.h"

namespace qm3d::mesh {

struct GeodesicPsimOptions : RunOptions {
  /// Keypoints (the reference's --N); min(keypoints, reference vertices after cleaning) are used.
  int keypoints = 5000;
};

/// One keypoint's patches and their similarities.
struct GeodesicPsimKeypoint {
  std::array<double, 3> position{};  ///< the keypoint (a vertex of the cleaned reference)
  /// 0 skipped (a patch of <= 3 vertices); 1, 2, 3 by the centres' shift against the patch size;
  /// flag-3 patches count only when no flag-1/2 patch exists.
  int flag = 0;
  double center_shift = 0;
  double patch_size = 0;
  int ref_texels = 0, dis_texels = 0;  ///< texels of the shrunk patches
  /// The per-patch similarities (NaN when the patch is skipped): pcs, dmc (after the
  /// negative-value fix), and Y/U/V mean and variance (lm, lvar, c1m, c1var, c2m, c2var).
  double pcs = 0, dmc = 0, lm = 0, lvar = 0, c1m = 0, c1var = 0, c2m = 0, c2var = 0;
  std::array<double, 3> ref_smoothness{}, dis_smoothness{};
  double ref_curvature = 0, dis_curvature = 0;
  bool pooled = false;  ///< entered the score
  /// The patch's own quality, (pcs + dmc + pca + pcv) / 4 (NaN when not pooled).
  double local_score() const;
};

struct GeodesicPsimResult {
  double score = 0;  ///< (pcs + dmc + pca + pcv) / 4
  double pcs = 0, dmc = 0, pca = 0, pcv = 0;
  int keypoints_used = 0;
  int flag1 = 0, flag2 = 0, flag3 = 0, skipped = 0;
  int effective_patches = 0;  ///< flag1 + flag2, or flag3 when there are none
  /// Which mesh was subdivided to equalise face counts: "none", "reference", "distorted".
  std::string subdivided = "none";
  std::vector<GeodesicPsimKeypoint> keypoints;
};

/// Scores `distorted_obj` against `reference_obj`: textured OBJ files (v, vt, f v/vt[/vn]
/// triangles; the texture is the MTL's map_Kd). InputError / FormatError naming the file for an
/// untextured mesh, a missing texture, a mesh without faces; NumericError when nothing is left
/// after cleaning. Same values for any thread count.
GeodesicPsimResult compute_geodesicpsim(const std::filesystem::path& reference_obj,
                                        const std::filesystem::path& distorted_obj,
                                        const GeodesicPsimOptions& options = {});

/// The registry entry (qm3d/common/metric.h): `qm3d geodesicpsim`.
MetricSpec geodesicpsim_spec();

}  // namespace qm3d::mesh
