// `qm3d batch`: scores every pair of a list, appending one CSV row per pair as soon as it is done.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "qm3d/scoring/score.h"
#include "qm3d/report/html_report.h"
#include "qm3d/study/shard.h"

namespace qm3d::study {

/// How far a batch has got: rows (one per pair and metric) and pairs (done when each of its rows
/// is), for a caller that shows it (the qm3d tool: apps/progress_display.h).
struct BatchProgress {
  std::size_t rows_done = 0, rows_total = 1;  ///< rows_total is at least 1
  std::size_t pairs_done = 0, pairs_total = 0;
  std::size_t failed = 0;  ///< rows done that record an error
  double elapsed_s = 0;    ///< since the batch started scoring
  double eta_s = 0;        ///< the time left, estimated from the rows done
};

/// "7/7 pairs" when every pair has one row, else "12/60 rows, 4/20 pairs".
std::string progress_counts(const BatchProgress& p);

/// Told after each row is done (from any scoring thread, one call at a time).
using BatchProgressCallback = std::function<void(const BatchProgress&)>;

struct BatchOptions {
  std::filesystem::path list;    ///< CSV with columns reference,distorted[,metric]; metric is
                                 ///< a registered metric, compare (one row per metric that
                                 ///< applies) or auto (commands.h metrics_for)
  std::filesystem::path output;  ///< results CSV (appended to, row by row)
  int jobs = 1;                  ///< pairs scored at the same time
  int threads = 0;               ///< total threads (0 = all cores), shared among the jobs
  bool resume = false;           ///< skip pairs already in `output` (same settings only)
  bool retry_failed = false;     ///< with resume: score the error rows again (replacing them)
  bool overwrite = false;        ///< replace an existing `output`
  bool quiet = false;            ///< no progress (`progress` not called), no summary on stderr
  BatchProgressCallback progress;  ///< told after each row; empty = not shown
  scoring::ScoreRequest request;          ///< run options (threads set per job) and metric options
  std::optional<Shard> shard;    ///< score only this part of the pairs (--shard K/N)
  /// One HTML report per pair (report_file_name()) and an index of the results, sorted by score
  /// (index.html; index-K-of-N.html for a shard); empty = none. A pair's report holds the
  /// metrics scored in this run (with --resume, not the rows already done).
  std::filesystem::path report_dir;
  report::ReportSettings report;  ///< how the reports are drawn (when report_dir is set)
  /// Score the jobs (a row each; with report_dir, a pair's rows) in worker processes, one per
  /// concurrent job, each scoring job after job and restarted after a fault, so that a fatal
  /// fault (signal, abort, memory, pair_timeout_s) is that job's error rows, not the batch's
  /// end. The workers run `program` with the hidden --batch-worker and `command_line`.
  bool isolate = true;
  double pair_timeout_s = 0;  ///< kill a worker after this long (isolate only); 0 = no limit
  /// The named-value columns of the results (csv_header): those of every metric the whole list
  /// names (compare: all metrics), so that shards and resumed runs share one header. Set by
  /// run_batch / run_batch_worker from the list.
  std::vector<std::string> value_names;
  /// The texture maps of each (reference, distorted) of the list (its ref_texture and
  /// dist_texture columns, as written there). Set by run_batch / run_batch_worker from the list.
  std::map<std::pair<std::string, std::string>, std::pair<std::string, std::string>> textures;
  std::string program;        ///< argv[0]
  std::vector<std::string> command_line;  ///< argv[1..]: this batch's own arguments
};

/// A list's relative path resolved against the list's folder.
std::filesystem::path resolve(const std::filesystem::path& list, const std::string& path);

/// The metric rows batch writes for a pair, in its order: "compare" is one row per metric that
/// applies and "auto" the first that applies (commands.h metrics_for), so that --resume and
/// merge key rows by (reference, distorted, metric); inputs that cannot be recognised keep the
/// name as written (scoring them records why).
std::vector<std::string> batch_metrics(const ListPair& pair, const std::filesystem::path& list);

/// Runs the batch. The results hold batch_header()'s columns (batch_results.h); the output is
/// locked while the batch runs. Returns 0 when every row of the results (this run's and, with
/// --resume, earlier ones') is ok, 2 when some row records an error or a report could not be
/// written (said on stderr). Throws InputError / FormatError when the list or the output cannot
/// be used: the output is the list, is being written by another batch, exists (without
/// --resume / --overwrite), or with --resume is not a batch results file or holds rows scored
/// with other settings.
int run_batch(const BatchOptions& options);

/// The worker of an isolated batch (`qm3d --batch-worker batch ...`, started by run_batch):
/// reads jobs from stdin, one line each ("THREADS,REFERENCE,DISTORTED,METRIC..." as CSV
/// fields), and for each writes its rows on stdout as soon as each is scored, writes the pair's
/// report (report_dir), then the line kJobEnd (pair_process.h), followed by " report-failed"
/// when the report could not be written. Returns 0 at the end of stdin.
int run_batch_worker(const BatchOptions& options);

}  // namespace qm3d::study
