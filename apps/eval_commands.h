// `qm3d eval` (agreement of objective scores with subjective scores) and `qm3d train` (feature
// weights fitted to subjective scores, written as a model file for `--model`).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace qm3d::app {

/// `qm3d eval SCORES.csv MOS.csv` (see README "qm3d eval").
struct EvalCommandOptions {
  std::string scores, mos;    ///< the two CSV files
  std::string scores_key;     ///< default: "distorted" when present (batch results), else column 1
  std::string scores_column;  ///< default: "score", else the other column of a 2-column file
  std::string mos_key;        ///< default: column 1
  std::string mos_column;     ///< default: "mos" (any case), else the other column of 2
  std::string ci_column;      ///< MOS 95% CI half-widths; enables the outlier ratio
  bool stem = false;          ///< match keys by file stem
  std::string orientation = "auto";  ///< auto, distortion, quality
  std::vector<std::string> lower_is_better;  ///< series that are distortions (Krasula)
  // Krasula's pair labels: from SD and n (or CI) of the MOS file, raw scores, or given.
  std::string sd_column, n_column;  ///< MOS columns
  std::string raw;                  ///< long format: stimulus, observer, score
  std::string pairs;                ///< first, second, label
  std::string group_column;         ///< MOS column: only pairs within a group
  std::string mapping;              ///< empty: the one-column logistic4 evaluation
  std::vector<std::string> more_scores;  ///< more SCORES files, their metrics beside SCORES's
  std::size_t bootstrap = 1000;
  std::uint64_t seed = 1;
  bool json = false, csv = false;
  std::string output;  ///< empty = stdout
  std::string plot;    ///< .svg or .png
};

/// `qm3d train FEATURES.csv MOS.csv --group-by COLUMN` (see README "qm3d train").
struct TrainCommandOptions {
  std::string features, mos;
  std::string features_key;  ///< as EvalCommandOptions::scores_key
  std::string mos_key, mos_column;
  /// "auto", or column prefixes whose columns PREFIX1..PREFIX8 are averaged ("f",
  /// "dist_to_ref_f,ref_to_dist_f").
  std::string feature_columns = "auto";
  std::vector<std::string> group_by;            ///< one or more columns (FEATURES first, then MOS)
  std::string metric;                           ///< default: FEATURES' metric column
  std::vector<std::string> subsets;             ///< default: all 255
  std::string criterion = "plcc";               ///< plcc, srocc, both
  std::string select = "one-se";                ///< one-se, best
  std::string final_weights = "mean-of-folds";  ///< mean-of-folds, refit
  bool stem = false;
  bool json = false;
  std::string output;  ///< the model file
  std::string report;  ///< every subset, .csv or .json
};

/// The two subcommands and the values CLI11 parses their options into.
struct EvalCommands {
  CLI::App* eval = nullptr;
  CLI::App* train = nullptr;
  EvalCommandOptions eval_options;
  TrainCommandOptions train_options;
};

/// Registers `eval` and `train` on `app`. `add_common` adds the options every command accepts
/// (--threads, --quiet, ...). The result must outlive app.parse(): CLI11 writes into it.
std::unique_ptr<EvalCommands> add_eval_commands(CLI::App& app,
                                                const std::function<void(CLI::App*)>& add_common);

/// Runs `eval` or `train` when one of them was parsed and returns its exit code; nullopt when
/// another command was parsed. Warnings go to stderr unless `quiet`.
std::optional<int> run_eval_commands(const EvalCommands& commands, bool quiet);

}  // namespace qm3d::app
