// How the tool shows progress on stderr: a line rewritten in place on a terminal, one line per
// stage otherwise (when asked for with --progress).
#pragma once

#include <string>

#include "qm3d/common/progress.h"
#include "qm3d/study/batch.h"

namespace qm3d::app {

/// "1h2m3s", "4m5s", "6s"; "?" for a negative or non-finite time.
std::string format_duration(double seconds);

/// True when stderr is a terminal.
bool stderr_is_terminal();

/// On a terminal, erases the stderr line a progress line may stand on (before an error message);
/// nothing otherwise.
void clear_progress_line();

/// A callback that shows `metric`'s progress on stderr: percentage, stage, the time elapsed
/// since its first stage and an estimate of the time left. `in_place`: rewrite one line (a
/// terminal) as the metric reports and at least every half second (a ticker thread, stopped
/// when the metric is done or the last copy of the callback is destroyed), erased when the
/// metric is done; otherwise print a line per stage.
ProgressCallback stderr_progress(const std::string& metric, bool in_place);

/// A callback that shows a batch's progress on stderr: on a terminal a bar rewritten in place
/// ("[###...] 12/60 rows, 4/20 pairs (1 failed)  ETA 4m5s"), otherwise a line at most every ten
/// seconds and at the end ("batch: ... done (1 failed), elapsed 6s, ETA 0s").
study::BatchProgressCallback stderr_batch_progress();

}  // namespace qm3d::app
