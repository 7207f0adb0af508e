// The evaluation protocol of several metrics on one set of stimuli, as `qm3d eval` and Python's
// qm3d.evaluate() run it: per metric the correlations after a mapping (evaluation.h), Krasula's
// AUC analysis when the subjective data allow pairs to be labelled (krasula.h), and the tests
// between every two metrics. The result is the JSON that `qm3d eval --json` writes.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "qm3d/evaluation/evaluation.h"
#include "qm3d/evaluation/krasula.h"
#include "qm3d/evaluation/p1401.h"

namespace qm3d::evaluation {

/// One metric's scores on the stimuli (aligned with SubjectiveData).
struct MetricScores {
  std::string name;
  std::vector<double> scores;
  /// Higher is better (a quality). Krasula's BW analysis and C0 negate the differences of a
  /// distortion (false).
  bool higher_is_better = true;
  /// Where the orientation comes from ("registered metric psnr", "--lower-is-better",
  /// "assumed: not a registered metric").
  std::string orientation_source;
};

/// The subjective data of the stimuli.
struct SubjectiveData {
  std::vector<double> mos;
  std::vector<double> ci95;  ///< MOS 95 % CI half-widths, or empty
  /// The pairs for Krasula's analysis, labelled (from SD and n, raw scores or a file); absent =
  /// no Krasula analysis.
  std::optional<PairLabels> pairs;
};

struct ProtocolOptions {
  /// The bootstrap of PLCC, SROCC and KROCC (and of the logistic4 fit it refits).
  EvaluationOptions evaluation;
  /// The mapping of the scores to the MOS scale before the P.1401 statistics.
  Mapping mapping = Mapping::logistic4;
};

/// The numbers of the evaluation.
struct ProtocolResult {
  std::vector<EvaluationResult> evaluations;  ///< one per metric, in order
  std::vector<P1401Evaluation> p1401;         ///< the mapping and its statistics, per metric
  std::optional<KrasulaResult> krasula;       ///< when SubjectiveData::pairs is given
};

/// Runs the evaluation (each metric's statistics; Krasula's analysis of all metrics together,
/// each distortion's scores negated).
/// @throws NumericError, std::invalid_argument  as evaluate_scores() and krasula_analysis(), two
///                                              metrics of one name
ProtocolResult run_protocol(const std::vector<MetricScores>& metrics,
                            const SubjectiveData& subjective, const ProtocolOptions& options = {});

/// The JSON of the evaluation: "stimuli", "metrics": {NAME: {"orientation", "statistics":
/// {plcc, srocc, krocc (bootstrap intervals), plcc_mapped, rmse_mapped[, rmse_star,
/// outlier_ratio] (P.1401's analytic intervals)}, "mapping" {name, parameters, ...},
/// "krasula": {auc_ds, auc_bw, c0, thr, thr_prctile, se_ds, se_bw, different, similar}}},
/// "krasula": {rule, pairs, different, better, similar} (or null), and "comparisons": [{a, b,
/// test, statistic, p}] for every a before b: fisher_z_plcc, f_rmse[, f_rmse_star,
/// outlier_ratio] (P.1401), then with pairs delong_auc_ds, delong_auc_bw, c0 (Krasula).
nlohmann::ordered_json protocol_json(const std::vector<MetricScores>& metrics,
                                     const SubjectiveData& subjective, const ProtocolResult& r);

/// run_protocol() and protocol_json() (what Python's qm3d.evaluate() returns).
nlohmann::ordered_json evaluate_metrics(const std::vector<MetricScores>& metrics,
                                        const SubjectiveData& subjective,
                                        const ProtocolOptions& options = {});

}  // namespace qm3d::evaluation
