// `qm3d demo`: scores the small stimuli bundled in data/ and prints a table.
#pragma once

#include <filesystem>
#include <ostream>

#include "qm3d/scoring/score.h"
#include "qm3d/report/html_report.h"

namespace qm3d::app {

/// The bundled data folder of this build (the source tree's data/).
std::filesystem::path default_demo_dir();

/// Scores every bundled pair with every registered metric that applies and prints the table to
/// `out`, then writes the HTML report of one pair (the blob3 mesh with geometric and colour
/// noise) into `report.file` (a folder; empty = a new folder in the system's temporary
/// directory) and prints its path. Without three.js the report is skipped with a warning, unless
/// a folder was given (then InputError). Returns the exit code.
int run_demo(const std::filesystem::path& dir, const scoring::ScoreRequest& request,
             const report::ReportCli& report, bool quiet, std::ostream& out);

}  // namespace qm3d::app
