// Krasula's pair labels from whatever subjective data a study has: per-stimulus SD and observer
// count (or the count from the MOS confidence intervals), raw individual scores, or labels given
// by the user. The one rule `qm3d eval` and Python's qm3d.evaluate() both apply.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "qm3d/evaluation/krasula.h"

namespace qm3d::evaluation {

/// z of a two-sided 95 % normal interval: CI half-width = 1.96 SD / sqrt(n).
inline constexpr double kZ95 = 1.959963984540054;

/// Where the labels come from: exactly one source (or none: no Krasula analysis).
struct PairLabelSource {
  enum class Kind { none, sd, raw, given };
  Kind kind = Kind::none;
  std::vector<double> sd, n;             ///< Kind::sd: each stimulus' SD and observer count
  std::vector<std::vector<double>> raw;  ///< Kind::raw: each stimulus' individual scores
  PairLabels given;                      ///< Kind::given: labelled pairs of stimulus indices
};

/// The observer count of a stimulus from its SD and 95 % CI half-width: n = (1.96 SD / CI)^2;
/// 0 (refused as fewer than 2 observers) when the CI is not positive.
double observers_from_ci(double sd, double ci95);

/// The labelled pairs of the stimuli (`mos`, one per stimulus): Krasula's 95 % z test on SD and
/// n (label_pairs_j149), VMAF's |z| > 2 on raw scores (label_pairs_raw), or the given pairs;
/// nullopt for Kind::none. `groups` (one per stimulus, or empty) keeps pairs within a group.
/// @throws std::invalid_argument  as label_pairs_j149() / label_pairs_raw()
std::optional<PairLabels> label_pairs(const std::vector<double>& mos, const PairLabelSource& source,
                                      const std::vector<std::string>& groups = {});

}  // namespace qm3d::evaluation
