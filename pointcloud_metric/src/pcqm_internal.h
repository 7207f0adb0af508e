// PCQM internals shared by pcqm.cpp and the tests: one direction of the metric with optional
// per-point diagnostics (the values MEPP-team/PCQM holds per point, for comparing with its dumps).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "qm3d/common/color.h"
#include "qm3d/common/features.h"
#include "qm3d/common/large_arrays.h"
#include "qm3d/common/progress.h"
#include "qm3d/common/types.h"

namespace qm3d::pointcloud::detail {

/// Everything one direction needs, already resolved from PcqmOptions.
struct DirectionParams {
  double max_dim = 0;          ///< bounding-box size: scales the radii and the curvatures
  double radius_rel = 0.004;   ///< r = radius_rel * max_dim
  double radius_factor = 2.0;  ///< statistics radius = radius_factor * r
  std::size_t knn = 20;        ///< k of the correspondence kNN (already <= #points allowed)
  int threads = 0;             ///< 0 = OpenMP default
  bool diagnostics = false;    ///< fill DirectionOutput::diagnostics
  /// Optional: told each of the direction's kProgressSteps stages, prefixed with `label`.
  ProgressSteps* progress = nullptr;
  std::string label;
  /// Optional: called once the direction holds its own copies of the two clouds (search trees,
  /// colours); the clouds are not read afterwards.
  std::function<void()> inputs_done;
};

/// Stages compute_direction reports: search trees, curvatures and correspondences, features.
inline constexpr int kProgressSteps = 3;

/// Per-point intermediate values, in the iterated cloud's input order (SPEC-PCQM 1.4, 1.5).
struct PointDiagnostics {
  std::vector<Vec3> correspondence;        ///< p-hat: foot point on D or nn_D(p)
  std::vector<double> curvature_iterated;  ///< k_R = |H| maxDim from R's points within r
  std::vector<double> curvature_other;     ///< k_D = |H| maxDim from D's points within r
  std::vector<Lab> lab_iterated;           ///< LAB2000HL of p's colour
  std::vector<Lab> lab_other;              ///< LAB2000HL of nn_D(p)'s colour
  std::vector<double> chroma_iterated, chroma_other, hue_difference;
  std::vector<std::uint32_t> count_radius_other;     ///< #D points within r
  std::vector<std::uint32_t> count_radius_iterated;  ///< #R points within r
  std::vector<std::uint32_t> count_statistics;       ///< #R points within radius_factor r
  /// Bits kCurvatureFit (k_D's or k_R's fit) and kMatchFit (p-hat's fit) when underdetermined.
  std::vector<std::uint8_t> underdetermined;
};

inline constexpr std::uint8_t kCurvatureFit = 1;
inline constexpr std::uint8_t kMatchFit = 2;

/// Share of points with an underdetermined fit of one kind above which compute_direction looks
/// for settings that avoid them (and compute_pcqm warns).
inline constexpr double kUnderdeterminedShare = 0.01;

/// Settings under which few fits are underdetermined (0 = none found or not measured).
struct Suggestion {
  double radius_rel = 0;  ///< curvature radius (fraction of max_dim)
  std::size_t knn = 0;    ///< k of the correspondence kNN
};

struct DirectionOutput {
  /// f1..f8 of each point (f4..f8 as 1 - similarity), in the iterated cloud's input order.
  LargeArray<FeatureVector> features;
  /// F1..F8 pooled as the reference pools them (pooling.h mean_features_from_similarities).
  FeatureVector pooled{};
  /// Points whose k_D or k_R fit, and points whose p-hat fit, is underdetermined
  /// (quadric_fit.h): their curvatures or p-hat depend on the linear-algebra library's rounding
  /// (SPEC-PCQM §9.5).
  std::size_t underdetermined_curvature = 0;
  std::size_t underdetermined_match = 0;
  /// Measured only for a kind of fit underdetermined on more than kUnderdeterminedShare of the
  /// points.
  Suggestion suggestion;
  PointDiagnostics diagnostics;  ///< empty unless DirectionParams::diagnostics
};

/// The reference's bounding-box size: max over axes of |min| + |max|, max starting at DBL_MIN
/// (PointSet.h `read_ply_file`). `positions` must not be empty.
double reference_max_dim(const std::vector<Vec3>& positions);

/// One direction of PCQM: iterates `iterated`'s points (the reference's R in the reference
/// tool's direction), finds their correspondences on `other` (its D).
/// Both clouds must be non-empty with one colour per point (compute_pcqm checks this); they are
/// not read after params.inputs_done is called.
/// Deterministic: bit-identical for any thread count.
DirectionOutput compute_direction(const ColoredCloud& iterated, const ColoredCloud& other,
                                  const DirectionParams& params, const Lab2000hlTable& table);

}  // namespace qm3d::pointcloud::detail
