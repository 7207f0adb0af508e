// The command-line face of the metric registry: each metric's own options become --NAME options
// (typed, range-checked, with their defaults and help), and --direction / --symmetric /
// --weights / --model become the run options. Adding a metric needs no change here.
#pragma once

#include <CLI/CLI.hpp>
#include <map>
#include <string>
#include <vector>

#include "qm3d/scoring/score.h"

namespace qm3d::app {

// The values of the metrics' own options as given on the command line (before conversion).
struct MetricOptionsCli {
  std::map<std::string, std::string> text;  // name -> value as typed
  std::map<std::string, std::vector<std::string>> lists;  // list options: the values as typed
  std::map<std::string, bool> flags;        // boolean options
  std::map<std::string, CLI::Option*> given;
};

// --direction / --symmetric, --weights / --model: the run options every metric command has.
struct RunCli {
  std::string direction;
  bool symmetric = false;
  std::vector<double> weights;
  std::string model_file;
};

/// Every registered metric, in registration order.
std::vector<const MetricSpec*> all_metrics();
/// The metrics compare and report may run (in_compare), in registration order: only their
/// options are theirs (ibsm's --views, --save-views ... would be accepted and ignored).
std::vector<const MetricSpec*> compare_metrics();
/// The tool's flag of a metric option: "--" + its name with '_' as '-' (color_space ->
/// --color-space; the Python keyword keeps the name).
std::string cli_flag(const std::string& option);

/// Adds --NAME for each option of `specs`, once per name (compare and batch take the options of
/// every metric; a value given applies to each metric that has an option of that name).
void add_metric_options(CLI::App* cmd, const std::vector<const MetricSpec*>& specs,
                        MetricOptionsCli& cli);

/// The options given, converted to their types (checked later against each metric's spec);
/// std::invalid_argument naming the option for a value that is not of its type.
OptionValues metric_option_values(const std::vector<const MetricSpec*>& specs,
                                  const MetricOptionsCli& cli);

/// Adds --direction and --symmetric, and --weights / --model when `spec` takes a model (compare
/// and batch, `spec` null: --model, applied to the metric the file names).
void add_run_options(CLI::App* cmd, RunCli& r, const MetricSpec* spec);

/// Adds --colour-scale (auto, unit or byte: the scale of colours stored as numbers, reading.h).
void add_read_options(CLI::App* cmd, std::string& colour_scale);

/// The read options of --colour-scale's value.
ReadOptions read_options(const std::string& colour_scale);

/// Adds --ref-texture and --dist-texture (a texture map replacing a textured mesh's own,
/// ReadOptions::texture).
void add_texture_options(CLI::App* cmd, std::string& ref_texture, std::string& dist_texture);
/// The read options of --colour-scale with a texture map given by `texture_option`.
ReadOptions read_options(const std::string& colour_scale, const std::string& texture,
                         const std::string& texture_option);

/// The request of a metric command (`spec` set) or of compare / batch (`spec` null).
scoring::ScoreRequest score_request(const RunCli& r, const MetricSpec* spec, int threads,
                           const std::string& data_dir);

}  // namespace qm3d::app
