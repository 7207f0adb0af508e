// The options of `qm3d batch` that decide what happens to a pair that fails or hangs.
#pragma once

#include <CLI/CLI.hpp>

#include "qm3d/study/batch.h"

namespace qm3d::app {

/// Adds --retry-failed, --pair-timeout and --no-isolation to `batch_cmd`, parsed into `options`.
void add_batch_safety_options(CLI::App* batch_cmd, study::BatchOptions& options);

}  // namespace qm3d::app
