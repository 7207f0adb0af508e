// `qm3d eval` on several metrics, or with Krasula's analysis: reads the score columns, the
// subjective data (MOS, CI, SD and n, raw scores or labelled pairs) and prints what
// qm3d::evaluate_metrics() computes (common/include/qm3d/common/evaluation_protocol.h).
#pragma once

#include "eval_commands.h"
#include "score_table.h"

namespace qm3d::app {

/// True when `eval` needs the protocol (several score columns, a batch file of several metrics,
/// or subjective data for Krasula's analysis) rather than the one-column evaluation.
bool needs_protocol(const EvalCommandOptions& o, const CsvTable& scores);

/// Runs it on `scores` (the SCORES file, read); the exit code (warnings on stderr unless
/// `quiet`).
int run_eval_protocol(const EvalCommandOptions& o, const CsvTable& scores, bool quiet);

}  // namespace qm3d::app
