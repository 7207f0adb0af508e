// What every metric returns, and the run options every metric takes.
//
// CMDM, MSDM2 and PCQM compare a reference R and a distorted object D by iterating the elements
// (vertices, points) of one of them and matching each on the other. A *direction* names which
// object is iterated; a metric computes one direction or both (symmetric: the mean). One
// MetricResult type serves every metric, the tool's writers (result_io.h) and the bindings.
//
// Example:
//   qm3d::mesh::CmdmOptions o;               // a RunOptions plus CMDM's own options
//   o.direction = qm3d::Direction::kDistToRef;
//   const qm3d::MetricResult r = qm3d::mesh::compute_cmdm(ref, dist, o);
//   r.score; r.dist_to_ref->features; r.dist_to_ref->per_element;
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "qm3d/common/features.h"
#include "qm3d/common/pooling.h"
#include "qm3d/common/progress.h"
#include "qm3d/common/types.h"

namespace qm3d {

/// Which object's elements are iterated (and matched on the other).
enum class Direction {
  kSymmetric,  ///< both directions; the score is their mean
  kDistToRef,  ///< the distorted object's elements matched on the reference
  kRefToDist,  ///< the reference's elements matched on the distorted object
};

/// "symmetric", "dist-to-ref", "ref-to-dist" (the tool's option values).
std::string direction_name(Direction d);
/// The inverse of direction_name; std::invalid_argument for anything else.
Direction parse_direction(const std::string& name);

/// The run options every metric takes. Each metric's options derive from it (CmdmOptions,
/// Msdm2Options, PcqmOptions) and add their own.
struct RunOptions {
  /// Unset = the metric's documented default (CMDM symmetric, MSDM2 dist-to-ref, PCQM
  /// ref-to-dist, the reference tools' choices).
  std::optional<Direction> direction;
  /// OpenMP threads for every parallel part; 0 = the calling thread's OpenMP default. Results are
  /// bit-identical for any count.
  int threads = 0;
  /// Keep the per-element (per-vertex / per-point) local distortion in the result.
  bool per_element = true;
  /// Optional: told each stage as it starts; the result does not depend on it.
  ProgressCallback progress;
  /// Directory of the LAB2000HL tables; empty = resolve_data_dir() (color.h).
  std::filesystem::path data_dir;
  /// Feature weights replacing the metric's published model (metrics with a linear model only).
  std::optional<LinearModel> model;
  /// Optional: called once, as soon as the metric holds its own copies of what it needs of the
  /// two input objects; the metric does not touch them afterwards, so the caller may free them
  /// (the tool frees what it read from files: lower peak memory). Not called when the
  /// computation fails before that point.
  std::function<void()> inputs_done;
};

/// Values a metric reports by name instead of (or beside) f1..f8 (psnr: d1_mse, d1_psnr, ...), in
/// the metric's order; a name the metric could not compute is left out (psnr's d2_* without
/// normals). +inf is a legitimate value (the PSNR of identical clouds: JSON null, text and CSV
/// "inf"); NaN never is (run_metric rejects it).
using NamedValues = std::vector<std::pair<std::string, double>>;

/// The value of that name, or nullopt.
std::optional<double> find_value(const NamedValues& values, const std::string& name);

/// One direction of a metric.
struct DirectionResult {
  double score = 0;          ///< the direction's pooled score
  FeatureVector features{};  ///< the pooled features (names in MetricResult::feature_names)
  /// The box size that scales the metric's radii and curvatures, measured on the iterated
  /// object: CMDM/MSDM2 the longest bounding-box side; PCQM its maxDim (with the reference's
  /// box mode, max over axes of |min| + |max|, not a side).
  double box_size = 0;
  /// Local distortion of each element of the iterated object, in its input order; empty when
  /// RunOptions::per_element is false.
  std::vector<double> per_element;
  /// The metric's named values of this direction (MetricSpec::value_names); empty for the
  /// metrics whose features are f1..f8.
  NamedValues values;
  /// Further per-element values by name, each like per_element (psnr: "c0".."c2", each point's
  /// squared colour error per channel); maps write them as scalar_NAME.
  std::vector<std::pair<std::string, std::vector<double>>> per_element_values;
  /// Where each per-element value is, when not on the input's elements
  /// (MetricSpec::per_element_positions: GeodesicPSIM's keypoints); empty otherwise.
  std::vector<Vec3> element_positions;
};

/// Where a result comes from: enough to reproduce it.
struct Provenance {
  std::string version;     ///< qm3d version that computed it
  std::string reproduces;  ///< MetricSpec::reproduces of the metric (empty: none)
  std::string reference;   ///< the reference's file (or a description of in-memory data)
  std::string distorted;   ///< the distorted object's file (or description)
  /// Every option used, the resolved table directory included (as the JSON output echoes it).
  nlohmann::json options = nlohmann::json::object();
  double seconds = 0;      ///< wall time of the computation (reading included when read here)
};

/// What a warning line (MetricResult::warnings) leaves out: written in the JSON's
/// `warning_details` (warning.h builds both).
struct WarningDetails {
  std::string warning;  ///< the line, as in MetricResult::warnings
  std::string details;  ///< the rest: full file names, the rule, the numbers
};

/// The result of one metric on one pair.
struct MetricResult {
  std::string metric;  ///< "cmdm", "msdm2", "pcqm", ...
  double score = 0;    ///< the requested direction's score, or the mean of both
  std::optional<DirectionResult> dist_to_ref;  ///< the distorted object iterated
  std::optional<DirectionResult> ref_to_dist;  ///< the reference iterated
  /// Names of the eight feature entries ("f1".."f8" for the mesh metrics, "F1".."F8" for PCQM,
  /// each paper's notation).
  std::vector<std::string> feature_names;
  /// Repairs and caveats, each one line of at most kMaxWarningLine characters naming the cause
  /// and the remedy (warning.h; also printed by the tool).
  std::vector<std::string> warnings;
  /// The details of the warnings that have more to say (the JSON's `warning_details`).
  std::vector<WarningDetails> warning_details;
  Provenance provenance;
  /// The named values of the result as a whole (psnr: pc_error's symmetric "Final" values, or
  /// the one direction's); written as the JSON's top-level `features`. Empty for f1..f8 metrics.
  NamedValues values;
  /// Further top-level JSON entries of the metric (psnr: peak, point counts, duplicates).
  nlohmann::json details = nlohmann::json::object();
  /// What the human line ends with, when the metric has more to say than its scores (psnr: the
  /// symmetric D1/D2/colour PSNRs and the peak).
  std::string text_note;

  /// The direction that was computed, or (symmetric) dist_to_ref when `prefer_dist` else
  /// ref_to_dist. Throws std::logic_error when none is set.
  const DirectionResult& any_direction(bool prefer_dist = true) const;
  /// The direction computed: kSymmetric when both are set.
  Direction direction() const;
};

/// Seconds elapsed since `start` (for Provenance::seconds).
inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// "f1".."f8" (prefix "f") or "F1".."F8" (prefix "F").
std::vector<std::string> feature_names(const std::string& prefix);

/// Sets `result.score` from its directions: their mean when both are set, else the one set (the
/// same rule for every metric). Throws std::logic_error when none is set.
void combine_directions(MetricResult& result);

}  // namespace qm3d
