// `qm3d merge SHARD.csv... -o RESULTS.csv --list LIST.csv`: joins the results of `qm3d batch
// --shard K/N` runs into the rows one `qm3d batch` over LIST would have written, and the
// `--shard K/N` option of `qm3d batch` (see README "Scoring a database on a cluster").
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "qm3d/study/shard.h"

namespace qm3d::app {

/// The subcommand and the values CLI11 parses its options into.
struct MergeCommand {
  CLI::App* merge = nullptr;
  std::vector<std::string> inputs;  ///< results CSVs of the shards
  std::string output;               ///< merged results (written atomically)
  std::string list;                 ///< the list the shards were cut from
  bool partial = false;             ///< write the rows found even when some are missing
};

/// Registers `merge`; `add_common` adds --threads, --quiet, ... The result must outlive
/// app.parse().
std::unique_ptr<MergeCommand> add_merge_command(CLI::App& app,
                                                const std::function<void(CLI::App*)>& add_common);

/// Runs `merge` when it was parsed and returns its exit code (0: every pair present and ok; 2:
/// some pair failed, is missing or conflicts); nullopt when another command was parsed.
/// Summary and warnings go to stderr unless `quiet`; errors always do.
std::optional<int> run_merge_command(const MergeCommand& command, bool quiet);

/// Adds `--shard K/N` to `batch_cmd`, parsed (with a usage error for a bad value) into `shard`.
void add_shard_option(CLI::App* batch_cmd, std::optional<study::Shard>& shard);

}  // namespace qm3d::app
