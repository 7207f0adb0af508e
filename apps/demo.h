// `qm3d demo`: scores the small stimuli bundled in data/ and prints a table.
#pragma once

#include <filesystem>
#include <ostream>

#include "commands.h"

namespace qm3d::app {

/// The bundled data folder of this build (the source tree's data/).
std::filesystem::path default_demo_dir();

/// Scores every bundled pair with every registered metric that applies and prints the table to
/// `out`. Returns the exit code.
int run_demo(const std::filesystem::path& dir, const ScoreRequest& request, std::ostream& out);

}  // namespace qm3d::app
