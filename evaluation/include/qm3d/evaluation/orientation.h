// Whether a higher score is better: the one orientation rule of `qm3d eval` (one column or
// several) and of Python's qm3d.evaluate(). A distortion's scores are negated in Krasula's
// analysis and a metric ranking against its orientation is warned about, so every caller must
// agree on it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "qm3d/common/metric.h"

namespace qm3d::evaluation {

/// What the caller was told about orientation, and how it spells those options in the
/// "orientation.from" it reports ("--lower-is-better" on the command line, "lower_is_better" in
/// Python).
struct OrientationRequest {
  std::vector<std::string> lower_is_better;  ///< series that are distortions
  std::string orientation = "auto";          ///< auto, quality (all) or distortion (all)
  std::string lower_is_better_option = "--lower-is-better";
  std::string orientation_option = "--orientation";
};

/// One score series: its name (as lower_is_better names it), the registered metric its rows
/// name (a batch file's "metric" column; empty when none) and its column ("score", "d1_mse").
struct SeriesName {
  std::string name;
  std::string metric;
  std::string column;
};

/// An orientation and where it comes from; `higher_is_better` unset = unknown.
struct Orientation {
  std::optional<bool> higher_is_better;
  std::string source;  ///< "--orientation", "metric column: psnr", "registered metric psnr", ...
};

/// How far the rule goes when neither the request nor the series' metric says.
enum class Fallback {
  /// Stop: unknown (the one-column evaluation reports it and does not warn).
  none,
  /// A column named after a registered metric or one of its named values, else assumed a
  /// quality (Krasula's convention), said so ("assumed: not a registered metric").
  column_name_then_quality,
};

/// The rule, first that applies: the series is named in lower_is_better (a distortion); an
/// orientation other than auto (every series); the registered metric the rows name, asked
/// about the column (MetricSpec::column_higher_is_better); then `fallback`.
Orientation orient(const Registry& registry, const OrientationRequest& request,
                   const SeriesName& series, Fallback fallback);

}  // namespace qm3d::evaluation
