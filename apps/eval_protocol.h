// `qm3d eval` on several metrics, or with Krasula's analysis: reads the score columns, the
// subjective data (MOS, CI, SD and n, raw scores or labelled pairs) and prints what
// qm3d::evaluate_metrics() computes (evaluation/include/qm3d/evaluation/evaluation_protocol.h).
#pragma once

#include "eval_commands.h"
#include "qm3d/evaluation/score_table.h"

namespace qm3d::app {

/// True when `eval` needs the protocol (several score columns, a batch file of several metrics,
/// or subjective data for Krasula's analysis) rather than the one-column evaluation.
bool needs_protocol(const EvalCommandOptions& o, const evaluation::CsvTable& scores);

/// Runs it on `scores` (the SCORES file, read); the exit code (warnings on stderr unless
/// `quiet`).
int run_eval_protocol(const EvalCommandOptions& o, const evaluation::CsvTable& scores, bool quiet);

/// "no stimulus in common between SCORES (key "k", e.g. "/d/a.ply") and MOS (key ..., e.g.
/// "a_1"), whole or by file stem (--stem); ...": one key of each side, for the error.
std::string no_common_key(const evaluation::CsvTable& scores, std::size_t scores_key, const evaluation::CsvTable& mos,
                          std::size_t mos_key);

/// Whether an SROCC of `rho` on `n` stimuli is clearly non-zero: |rho| sqrt(n - 1) > 1.96, the
/// two-sided 5% test of Spearman's rho under independence in its normal approximation (variance
/// 1 / (n - 1); Kendall & Stuart, The Advanced Theory of Statistics, vol. 2, 31.19). A metric
/// ranking against its orientation only this clearly is evidence, not a poor correlation.
bool clearly_nonzero(double rho, std::size_t n);

}  // namespace qm3d::app
