// D1 (point-to-point) and D2 (point-to-plane) PSNR, their Hausdorff distances and colour PSNR,
// exactly as MPEG's pc_error computes them (MPEGGroup/mpeg-pcc-dmetric 0.14.2, commit bd6df59,
// source/pcc_distortion.cpp and pcc_processing.cpp): the numbers point-cloud coding papers
// report next to PCQM.
//
// Per direction A -> B (A iterated, each point matched to its nearest neighbour in B): D1 is the
// mean squared distance, D2 the mean squared distance along B's normal (B's normals transferred
// from A's), colour the mean squared difference of the matched colours per channel; Hausdorff
// values are the largest squared distance (pc_error prints squares). Geometry PSNR is
// 10 log10(3 p^2 / mse) for the peak p, colour PSNR 10 log10(peak^2 / mse). The symmetric result
// takes the worse direction of each value (pc_error's "3. Final"). A is the reference.
//
// Example:
//   qm3d::pointcloud::PsnrOptions o;
//   o.peak = 1023;                                       // pc_error -r 1023
//   qm3d::MetricResult r = qm3d::pointcloud::compute_psnr(ref, ref_normals, dist, o);
//   r.score;                                              // symmetric D1 PSNR, dB
//   *qm3d::find_value(r.values, "c0_psnr");              // luma PSNR, dB
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "qm3d/common/grid_samples.h"
#include "qm3d/common/metric.h"
#include "qm3d/common/result.h"
#include "qm3d/common/types.h"

namespace qm3d::pointcloud {

/// The colour space of the colour MSE and PSNR (pc_error --mseSpace).
enum class PsnrColourSpace {
  kYCbCr,  ///< ITU-R BT.709 Y, Cb, Cr in [0, 1], peak 1 (mseSpace 1, pc_error's default)
  kRgb,    ///< R, G, B in 0..255, peak 255 (mseSpace 0)
  kYCoCg,  ///< YCoCg-R, Y in 0..255 (peak 255), Co and Cg in 0..511 (peak 511) (mseSpace 8)
};

/// What pc_error does with points of the same coordinates in one cloud (--dropdups).
enum class DuplicatePoints {
  kKeep = 0,     ///< detect only: all points stay
  kDrop = 1,     ///< keep the first of each run (in file order), drop the others
  kAverage = 2,  ///< keep one point whose colour is the run's mean (truncated; pc_error's default)
};

/// The colour matched to a point when several neighbours are at the same distance
/// (--neighborsProc).
enum class TiedNeighbours {
  kAverage = 1,          ///< their mean colour (pc_error's default)
  kWeightedAverage = 2,  ///< their mean weighted by how many duplicates each one merged
};

/// The normals D2 projects on in the pass A -> B.
enum class D2Normals {
  kTransferred,  ///< A's normals transferred to B's points (pc_error; mmetric
                 ///< --normalCalcModificationEnable=false)
  kOwn,          ///< B's own normals (mmetric's default; a mesh's grid samples carry their face's)
};

/// The names of MetricResult::values and of each direction's values, in this order (the colour
/// channels c0, c1, c2 are those of the colour space).
const std::vector<std::string>& psnr_value_names();

struct PsnrOptions : RunOptions {
  /// The peak p of the geometry PSNRs (pc_error -r, stored as float32 as pc_error stores it);
  /// unset = the largest nearest-neighbour distance in the reference, pc_error's default.
  std::optional<double> peak;
  PsnrColourSpace colour_space = PsnrColourSpace::kYCbCr;
  DuplicatePoints duplicates = DuplicatePoints::kAverage;
  TiedNeighbours tied = TiedNeighbours::kAverage;
  /// D2 over every neighbour at the nearest distance, each with its own normal, and normals
  /// transferred to B by averaging all of A's points at the nearest distance (pc_error
  /// --averageNormals=1, its default); false: the first neighbour only.
  bool average_normals = true;
  bool hausdorff = true;  ///< also the Hausdorff values (pc_error -d 1)
  bool colour = true;     ///< also the colour values (pc_error -c 1); both clouds need colours
  /// Normals for D2 computed as ../shared/tools/add_pca_normals.py does (k = 12, oriented
  /// outward from the centroid) instead of the reference's own.
  bool estimate_normals = false;
};

/// The normals of D2 (pc_error's cloudNormalsA).
struct ReferenceNormals {
  /// One per point: of the reference's points (in its order) when `positions` is empty, else
  /// of `positions` (a separate normals file, pc_error -n: pc_error pairs its points with the
  /// reference's by their order after sorting, so it must hold as many points).
  std::vector<Vec3> normals;
  std::vector<Vec3> positions;
  std::string name;  ///< the file, for messages (empty = the reference's own)
};

/// Computes pc_error's values of `distorted` (B) against `reference` (A).
///
/// @param[in] reference          #A points (colours, one per point, needed when options.colour)
/// @param[in] reference_normals  no normals (no D2, with a warning), the reference's own or a
///                               normals file's (ignored with options.estimate_normals)
/// @param[in] distorted          #B points
/// @param[in] options            see PsnrOptions; direction: symmetric (default, both passes as
///                               pc_error), ref-to-dist (A -> B alone, pc_error -s), dist-to-ref
/// @return score = the D1 PSNR of the requested direction (symmetric: the worse one); values
///         named by psnr_value_names() (+inf PSNR for a zero MSE; a zero Hausdorff is 0 with
///         an infinite PSNR, where pc_error prints DBL_MIN and a finite PSNR); per direction
///         the same values and, with per_element, each input point's D1 error (squared
///         distance, a merged duplicate taking its run's); details: peak, nn_min / nn_max
///         (computed peak), point counts and duplicates.
/// @throws FormatError   colours missing where colour is asked, normals not one per point or
///                       not finite
/// @throws NumericError  an empty cloud, non-finite coordinates, a peak that is not positive
MetricResult compute_psnr(const ColoredCloud& reference, const ReferenceNormals& reference_normals,
                          const ColoredCloud& distorted, const PsnrOptions& options = {},
                          const std::string& reference_name = "reference",
                          const std::string& distorted_name = "distorted");

/// How two meshes are compared the V-Mesh / V-DMC CTC way, with MPEG mmetric 1.1.7
/// (MPEGGroup/mpeg-pcc-mmetric @ 5faa660): both sampled on one grid (`mm sample --mode grid
/// --useNormal`, mesh/grid_sampling.h), then the two clouds compared as `mm compare --mode pcc`
/// does: pc_error's metric with a tie threshold of 1e-20 (pc_error: 1e-8), duplicate samples
/// merged with their normals averaged (unnormalised), D2 on B's own sampled normals.
struct MeshPsnrOptions : PsnrOptions {
  /// Grid nodes along the box's longest side (mm sample --gridSize; the CTC's 1024).
  int grid_size = 1024;
  /// The grid's box; unset = the union of the two meshes' vertex boxes (the CTC's).
  std::optional<FloatBox> box;
  D2Normals d2_normals = D2Normals::kOwn;
  bool bilinear = false;  ///< texture lookups of textured OBJ files bilinear (else nearest)
};

/// The tie threshold of mmetric's compare (its similarPointThreshold) and pc_error's.
constexpr double kMmetricTieThreshold = 1e-20;
constexpr double kPcErrorTieThreshold = 1e-8;

/// mmetric 1.1.7's `compare --mode pcc` on two clouds with their own normals (one per point, or
/// none): its duplicate merging with averaged (unnormalised) normals, D2 only when the reference
/// has normals, the pass reference -> distorted on the distorted cloud's own normals (d2_normals
/// kOwn, mmetric's default; kTransferred or a distorted cloud without normals: transferred from
/// the reference, --normalCalcModificationEnable=false), ties 1e-20, unset peak = the diagonal
/// of the reference's box before merging (float32, mmetric's --resolution 0). Values as
/// compute_psnr's (shared/data/reference/mpeg/clouds_pcc/).
MetricResult compute_psnr_mmetric(const ColoredCloud& reference,
                                  const std::vector<Vec3>& reference_normals,
                                  const ColoredCloud& distorted,
                                  const std::vector<Vec3>& distorted_normals,
                                  const PsnrOptions& options = {},
                                  D2Normals d2_normals = D2Normals::kOwn,
                                  const std::string& reference_name = "reference",
                                  const std::string& distorted_name = "distorted");

/// mmetric's values of two meshes (MeshPsnrOptions). Unset peak = mmetric's --resolution 0: the
/// diagonal of the reference's sampled cloud's box (float32). A mesh without vertex colours
/// gives geometry values only (with a warning). Details: how the meshes were sampled (grid
/// size, box, step, samples, duplicates, degenerate faces) and the conventions used.
/// @throws FormatError   an input that is not a mesh, a normals option (meshes carry theirs)
/// @throws NumericError  a grid that yields no samples, a non-finite box
MetricResult compute_mesh_psnr(const Input& reference, const Input& distorted,
                               const GridSampler& sampler, const MeshPsnrOptions& options = {});

}  // namespace qm3d::pointcloud
