// How the tool shows progress on stderr: a line rewritten in place on a terminal, one line per
// stage otherwise (when asked for with --progress).
#pragma once

#include <string>

#include "qm3d/common/progress.h"

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

}  // namespace qm3d::app
