// `qm3d batch`: scores every pair of a list, appending one CSV row per pair as soon as it is done.
#pragma once

#include <filesystem>
#include <optional>

#include "commands.h"
#include "html_report.h"
#include "shard.h"

namespace qm3d::app {

struct BatchOptions {
  std::filesystem::path list;    ///< CSV with columns reference,distorted[,metric]; metric is
                                 ///< a registered metric, compare (one row per metric that
                                 ///< applies) or auto (commands.h metrics_for)
  std::filesystem::path output;  ///< results CSV (appended to, row by row)
  int jobs = 1;                  ///< pairs scored at the same time
  int threads = 0;               ///< total threads (0 = all cores), shared among the jobs
  bool resume = false;           ///< skip pairs already in `output`
  bool overwrite = false;        ///< replace an existing `output`
  bool quiet = false;            ///< no progress on stderr
  ScoreRequest request;          ///< run options (threads set per job) and metric options
  std::optional<Shard> shard;    ///< score only this part of the pairs (--shard K/N)
  /// One HTML report per pair (report_file_name()) and an index of the results, sorted by score
  /// (index.html; index-K-of-N.html for a shard); empty = none. A pair's report holds the
  /// metrics scored in this run (with --resume, not the rows already done).
  std::filesystem::path report_dir;
  ReportSettings report;  ///< how the reports are drawn (when report_dir is set)
};

/// A list's relative path resolved against the list's folder.
std::filesystem::path resolve(const std::filesystem::path& list, const std::string& path);

/// The metric rows batch writes for a pair, in its order: "compare" is one row per metric that
/// applies and "auto" the first that applies (commands.h metrics_for), so that --resume and
/// merge key rows by (reference, distorted, metric); inputs that cannot be recognised keep the
/// name as written (scoring them records why).
std::vector<std::string> batch_metrics(const ListPair& pair, const std::filesystem::path& list);

/// Runs the batch. Returns 0 when every pair succeeded and 2 when some failed (their rows carry
/// the error) or a report could not be written (said on stderr). Throws InputError / FormatError when the list or the output cannot be used.
int run_batch(const BatchOptions& options);

}  // namespace qm3d::app
