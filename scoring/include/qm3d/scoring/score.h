// Scoring a pair by metric name, driven by default_registry(): which metrics run on a pair
// (metrics_for), with which options (ScoreRequest), and the distortion map (write_map). The tool,
// the study runner (qm3d::study) and Python score through these.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "qm3d/common/metric.h"
#include "qm3d/common/result.h"
#include "qm3d/scoring/registry.h"

namespace qm3d::scoring {

/// What a scoring command asks for, for every metric it runs.
struct ScoreRequest {
  RunOptions run;  ///< model unset: see `model`
  /// Values of the metrics' own options given on the command line (each metric takes the names
  /// it knows, options_for()).
  OptionValues options = OptionValues::object();
  /// Weights replacing the published model of the metrics whose model_name() is model->metric
  /// (every metric taking a model when `model_any_metric`).
  std::optional<LinearModel> model;
  bool model_any_metric = false;
  /// Keep the per-element values in the result (for a report) even when no map is written.
  bool keep_per_element = false;
  /// The caller uses neither input after this metric: what was read from their files is freed
  /// as soon as the metric holds its own copies (lower peak memory). Ignored when a map is
  /// written (it needs the iterated input's geometry).
  bool release_inputs = false;
  /// How the input files are read (--colour-scale).
  ReadOptions read;
};

/// The metrics a command or a batch row names for the pair: a metric's name, "auto" (the first
/// metric that applies: CMDM for two meshes, PCQM otherwise) or "compare" (every metric that
/// applies, in registration order).
std::vector<const MetricSpec*> metrics_for(const std::string& name, const Input& reference,
                                           const Input& distorted);

/// The run options of one metric of the request (model only where it applies).
RunOptions run_options_for(const MetricSpec& spec, const ScoreRequest& request);

/// Runs one metric; writes the distortion map when `map` is not empty.
MetricResult score(const MetricSpec& spec, const Input& reference, const Input& distorted,
                   const ScoreRequest& request, const std::filesystem::path& map = {});

/// Writes the per-element values of `result` on the iterated input's geometry (with faces for a
/// metric that reads meshes): the metric's default single direction when computed, else the
/// other (MEPP2 maps CMDM's dist->ref). InputError when the metric has no per-element values on
/// its inputs.
void write_map(const std::filesystem::path& map, const MetricSpec& spec, const MetricResult& result,
               const Input& reference, const Input& distorted);

}  // namespace qm3d::scoring
