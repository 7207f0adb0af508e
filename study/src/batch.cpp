#include "qm3d/study/batch.h"

#include <omp.h>
#include <sys/prctl.h>
#include <sys/wait.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>

#include "qm3d/study/batch_results.h"
#include "qm3d/scoring/score.h"
#include "pair_process.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/result_io.h"
#include "qm3d/study/batch_row.h"

namespace qm3d::study {
using namespace qm3d::scoring;  // NOLINT: the scoring the study runs
using namespace qm3d::report;  // NOLINT: the library this command drives
namespace {

// A batch's progress: rows (one per pair and metric) and pairs (done when each of its rows is),
// counted apart when a pair has several rows, told to BatchOptions::progress.
class Progress {
 public:
  Progress(const std::vector<std::pair<ListPair, std::string>>& todo, BatchProgressCallback show)
      : show_(std::move(show)), start_(std::chrono::steady_clock::now()) {
    p_.rows_total = std::max<std::size_t>(todo.size(), 1);
    for (const auto& [pair, metric] : todo) ++rows_left_[{pair.reference, pair.distorted}];
    p_.pairs_total = rows_left_.size();
  }

  void done_one(const std::string& row, bool failed) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++p_.rows_done;
    p_.failed += failed ? 1 : 0;
    const auto f = csv_split(row);
    if (f.size() > 1) {
      const auto it = rows_left_.find({f[0], f[1]});
      if (it != rows_left_.end() && it->second > 0 && --it->second == 0) ++p_.pairs_done;
    }
    if (!show_) return;
    p_.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    p_.eta_s = p_.elapsed_s / p_.rows_done * (p_.rows_total - p_.rows_done);
    show_(p_);
  }
  std::size_t failed() const { return p_.failed; }

 private:
  BatchProgress p_;
  BatchProgressCallback show_;
  std::map<std::pair<std::string, std::string>, std::size_t> rows_left_;
  std::chrono::steady_clock::time_point start_;
  std::mutex mutex_;
};

// One scored row: the CSV row and, when it succeeded, the result and its inputs (for a report).
struct ScoredRow {
  std::string row;
  bool failed = false;
  const MetricSpec* spec = nullptr;
  std::optional<MetricResult> result;
  std::optional<Input> reference, distorted;
};

ScoredRow failed_row(const ListPair& pair, const std::string& metric, const std::string& error,
                     const BatchOptions& o) {
  ScoredRow s;
  s.row = csv_error_row(pair.reference, pair.distorted, metric, error, o.value_names);
  s.failed = true;
  return s;
}

// --save-views DIR in a batch: each pair's views go to DIR/<its report name> (the same stems
// and hash of both paths), so that pairs, --jobs and shards never write over each other's.
void per_pair_views(OptionValues& options, const ListPair& pair) {
  const auto it = options.find("save_views");
  if (it == options.end() || !it->is_string() || it->get<std::string>().empty()) return;
  std::string folder = report_file_name(pair.reference, pair.distorted);
  folder.resize(folder.size() - std::string(".html").size());
  *it = (std::filesystem::path(it->get<std::string>()) / folder).string();
}

// Scores one pair; never throws (a failure becomes the row's error).
ScoredRow score_pair(const ListPair& pair, const std::string& metric, const BatchOptions& o) {
  const auto ref = resolve(o.list, pair.reference), dist = resolve(o.list, pair.distorted);
  try {
    ReadOptions ref_read = o.request.read, dist_read = o.request.read;
    if (const auto t = o.textures.find({pair.reference, pair.distorted}); t != o.textures.end()) {
      if (!t->second.first.empty()) ref_read.texture = resolve(o.list, t->second.first);
      if (!t->second.second.empty()) dist_read.texture = resolve(o.list, t->second.second);
    }
    ref_read.texture_option = "the list's ref_texture column";
    dist_read.texture_option = "the list's dist_texture column";
    const Input r = default_registry().read(ref, ref_read), d = default_registry().read(dist, dist_read);
    const auto specs = metrics_for(metric, r, d);
    ScoreRequest request = o.request;
    request.release_inputs = o.report_dir.empty();  // a report reads both inputs
    per_pair_views(request.options, pair);
    MetricResult result = score(*specs.front(), r, d, request);
    result.provenance.reference = pair.reference;
    result.provenance.distorted = pair.distorted;
    ScoredRow s{csv_row(result, {}, o.value_names), false, specs.front(), std::nullopt, r, d};
    if (!o.report_dir.empty()) s.result = std::move(result);
    return s;
  } catch (const MemoryLimitError& e) {
    return failed_row(pair, metric, std::string("out of memory: ") + e.what(), o);
  } catch (const std::bad_alloc&) {
    return failed_row(pair, metric, "out of memory", o);
  } catch (const std::exception& e) {
    return failed_row(pair, metric, e.what(), o);
  }
}

void make_report_dir(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) {
    throw InputError(dir.string() + ": cannot create the report folder (--report-dir)" +
                     (ec ? ": " + ec.message() : std::string()));
  }
}

// The reports of --report-dir: a pair's results are gathered until its last row of this run is
// scored, then its report is written (by the worker that scored that row).
class PairReports {
 public:
  PairReports(const BatchOptions& o, const std::vector<std::pair<ListPair, std::string>>& todo)
      : o_(o) {
    if (o.report_dir.empty()) return;
    make_report_dir(o.report_dir);
    for (const auto& [pair, metric] : todo) ++pending_[{pair.reference, pair.distorted}].left;
  }

  // Never throws: a report that cannot be written is recorded (errors()).
  void add(const ListPair& pair, ScoredRow&& s) {
    if (o_.report_dir.empty()) return;
    Pending done;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      Pending& p = pending_[{pair.reference, pair.distorted}];
      if (s.result) {
        p.results.emplace_back(s.spec, std::move(*s.result));
        p.reference = s.reference;
        p.distorted = s.distorted;
      }
      if (--p.left > 0) return;
      done = std::move(p);
      pending_.erase({pair.reference, pair.distorted});
    }
    if (done.results.empty()) return;  // every row failed: its errors are in the results
    try {
      write(pair, done);
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      errors_.push_back(e.what());
    }
  }

  // Writes the index of every row of `results` (this run's and earlier ones').
  void write_index(const std::filesystem::path& results) {
    if (o_.report_dir.empty()) return;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(results, ec)) {
      // A pipe or device (-o /dev/stdout): reading it back would take another reader's rows.
      std::lock_guard<std::mutex> lock(mutex_);
      errors_.push_back(results.string() +
                        ": not a regular file, so no index.html of its rows is written (the "
                        "pairs' reports are)");
      return;
    }
    std::vector<IndexRow> rows;
    std::istringstream in(read_file_bytes(results, kMaxTableBytes));
    std::string line;
    while (std::getline(in, line)) {
      const auto f = csv_split(line);
      if (f.size() < 6 || f[0] == "reference") continue;
      IndexRow r{f[0], f[1], f[2], std::nullopt, f[5], ""};
      if (f[4] == "ok" && !f[3].empty()) r.score = std::stod(f[3]);
      if (const MetricSpec* spec = default_registry().find(r.metric)) r.higher_is_better = spec->higher_is_better;
      const std::string name = report_file_name(r.reference, r.distorted);
      if (std::filesystem::exists(o_.report_dir / name)) r.report = name;
      rows.push_back(std::move(r));
    }
    const std::string index =
        o_.shard ? "index-" + std::to_string(o_.shard->index) + "-of-" +
                       std::to_string(o_.shard->count) + ".html"
                 : "index.html";
    write_report_index(o_.report_dir / index, rows,
                       "qm3d batch: " + o_.list.filename().string());
  }

  const std::vector<std::string>& errors() const { return errors_; }

 private:
  struct Pending {
    std::size_t left = 0;
    std::vector<std::pair<const MetricSpec*, MetricResult>> results;
    std::optional<Input> reference, distorted;
  };

  void write(const ListPair& pair, Pending& p) const {
    // Registration order, as compare prints them (rows may finish in any order).
    std::sort(p.results.begin(), p.results.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<ReportEntry> entries;
    for (const auto& [spec, result] : p.results) entries.push_back({spec, &result});
    write_html_report(o_.report_dir / report_file_name(pair.reference, pair.distorted), entries,
                      *p.reference, *p.distorted, o_.report);
  }

  const BatchOptions& o_;
  std::map<std::pair<std::string, std::string>, Pending> pending_;
  std::mutex mutex_;
  std::vector<std::string> errors_;
};

// What one job scores: a row, or with --report-dir every row of a pair (its report shows them
// together).
struct PairJob {
  ListPair pair;
  std::vector<std::string> metrics;
};

std::vector<PairJob> group_jobs(const std::vector<std::pair<ListPair, std::string>>& todo,
                                bool by_pair) {
  std::vector<PairJob> jobs;
  std::map<std::pair<std::string, std::string>, std::size_t> job_of_pair;
  for (const auto& [pair, metric] : todo) {
    const auto [it, fresh] =
        job_of_pair.emplace(std::pair(pair.reference, pair.distorted), jobs.size());
    if (by_pair && !fresh) {
      jobs[it->second].metrics.push_back(metric);
    } else {
      jobs.push_back({pair, {metric}});
    }
  }
  return jobs;
}

bool row_failed(const std::string& row) {
  const auto f = csv_split(row);
  return f.size() < 5 || f[4] != "ok";
}

/// Told each row as it is scored: the row (without the settings column) and whether it failed.
using RowDone = std::function<void(const std::string& row, bool failed)>;

// Scores a job's rows in this process (--no-isolation, and inside a worker).
void score_here(const PairJob& job, const BatchOptions& per_job, PairReports& reports,
                const RowDone& done) {
  for (const std::string& metric : job.metrics) {
    ScoredRow s = score_pair(job.pair, metric, per_job);
    done(s.row, s.failed);
    reports.add(job.pair, std::move(s));
  }
}

// The workers' command line: this run's own arguments (the same options, list and report
// folder) and the hidden --batch-worker.
std::vector<std::string> worker_args(const BatchOptions& o) {
  std::vector<std::string> args{o.program, "--batch-worker"};
  args.insert(args.end(), o.command_line.begin(), o.command_line.end());
  return args;
}

// The line that asks a worker for a job: threads, reference, distorted, metrics (CSV fields).
std::string job_line(const PairJob& job, int threads) {
  std::string line = std::to_string(threads) + "," + csv_field(job.pair.reference) + "," +
                     csv_field(job.pair.distorted);
  for (const std::string& m : job.metrics) line += "," + csv_field(m);
  return line;
}

// Ctrl-C reaches the whole process group and scancel every process of the job: the batch
// itself then ends by the signal's default action (it installs no handler for SIGINT, SIGTERM,
// SIGHUP or SIGQUIT) before it sees its workers end, so no row is written for the pairs in
// flight and --resume scores them. A worker that such a signal ended while its batch lives was
// stopped alone (an out-of-memory daemon such as earlyoom sends SIGTERM to the largest process,
// or someone killed it): that is its pair's error row, like a crash, and the batch goes on.

// Scores a job in a worker process: each row it writes, as it arrives, and for each row it did
// not write (it crashed, aborted, ran out of memory or time) an error row saying how it ended.
// False when the worker wrote every row but a report failed (said on stderr by the worker).
bool score_in_worker(const PairJob& job, WorkerProcess& worker, int threads, const BatchOptions& o,
                     const RowDone& done) {
  std::set<std::string> written;  // the job's metrics with a row
  const auto take_row = [&](const std::string& line) {
    const auto f = csv_split(line);
    if (f.size() > 4 && f[0] == job.pair.reference && f[1] == job.pair.distorted &&
        std::count(job.metrics.begin(), job.metrics.end(), f[2]) > 0 &&
        written.insert(f[2]).second) {
      done(line, row_failed(line));
    }
  };
  const JobOutcome w = worker.run(job_line(job, threads), o.pair_timeout_s, take_row);
  for (const std::string& metric : job.metrics) {
    if (written.count(metric) > 0) continue;
    done(csv_error_row(job.pair.reference, job.pair.distorted, metric,
                       describe_worker_end(w, o.pair_timeout_s), o.value_names),
         true);
  }
  return !w.finished || w.end_status.empty();
}

// Test hook, for tests/apps/batch_hostile_test.cpp only: QM3D_TEST_FAULT=KIND:NAME makes a
// worker fail as a crashing metric would on a pair whose distorted file is named NAME: KIND
// segv (SIGSEGV), abort (SIGABRT), term (SIGTERM, as an out-of-memory daemon sends) or hang
// (never returns), so that the tests need no input that crashes a metric (such inputs get
// fixed).
void test_fault(const ListPair& pair) {
  const char* fault = std::getenv("QM3D_TEST_FAULT");
  if (fault == nullptr) return;
  const std::string f(fault);
  const auto colon = f.find(':');
  if (colon == std::string::npos ||
      std::filesystem::path(pair.distorted).filename() != f.substr(colon + 1)) {
    return;
  }
  const std::string kind = f.substr(0, colon);
  // Default actions first: a sanitizer's handler would turn the signal into an exit code.
  if (kind == "segv") {
    std::signal(SIGSEGV, SIG_DFL);
    std::raise(SIGSEGV);
  }
  if (kind == "term") {
    std::signal(SIGTERM, SIG_DFL);
    std::raise(SIGTERM);
  }
  if (kind == "abort") {
    std::signal(SIGABRT, SIG_DFL);
    std::abort();
  }
  if (kind == "hang") {
    for (;;) std::this_thread::sleep_for(std::chrono::hours(1));
  }
}

BatchOptions job_options(const BatchOptions& o, int job_threads) {
  BatchOptions per_job = o;
  per_job.request.run.threads = job_threads;
  per_job.request.keep_per_element = !o.report_dir.empty();
  return per_job;
}

// The output must be none of the inputs: not the list (--resume would find no rows, --overwrite
// would erase it), nor a file of a pair (--overwrite would erase it).
void refuse_input_as_output(const BatchOptions& o, const std::vector<ListPair>& pairs) {
  if (same_file(o.list, o.output)) {
    throw InputError(o.output.string() + ": is the list itself (LIST and -o name the same file)");
  }
  if (!std::filesystem::exists(o.output)) return;
  for (const ListPair& p : pairs) {
    for (const std::string& input : {p.reference, p.distorted}) {
      if (same_file(resolve(o.list, input), o.output)) {
        throw InputError(o.output.string() + ": is an input of the list (" + input +
                         "), not a results file");
      }
    }
  }
}

// Opens, checks and prepares the results file: the rows --resume keeps (the error rows dropped
// with --retry-failed) and the header when the file is new.
std::set<RowKey> prepare_output(LockedResults& out, const BatchOptions& o,
                                const std::string& settings, bool existed) {
  ResumeState state;
  if (existed && o.resume) {
    if (!out.is_regular()) {
      throw InputError(o.output.string() + ": not a regular file (--resume continues a file)");
    }
    std::string text = read_file_bytes(o.output);
    const auto last_newline = text.find_last_of('\n');
    const std::size_t complete = last_newline == std::string::npos ? 0 : last_newline + 1;
    if (complete != text.size()) {  // a partial last line left by a kill
      std::filesystem::resize_file(o.output, complete);
      text.resize(complete);
    }
    state = read_resume(text, o.output.string(), settings, o.retry_failed, o.value_names);
    if (state.retried > 0 || state.widened) out.replace(state.kept_text);
  } else if (existed) {
    out.truncate();  // --overwrite
  }
  if (!state.has_header) out.write_line(batch_header(o.value_names));
  return state.done;
}

// What score_jobs did.
struct ScoringSummary {
  std::size_t failed_rows = 0;  ///< rows of this run that record an error
  bool reports_ok = true;       ///< false: a report could not be written (said on stderr)
};

// Scores the rows of `todo`, o.jobs jobs at a time, appending each row to `out` as it is done.
// Throws InputError when a row cannot be written (the jobs stop; the rows written stay).
ScoringSummary score_jobs(const BatchOptions& o, const std::vector<std::pair<ListPair, std::string>>& todo,
                LockedResults& out, const std::string& settings) {
  // A worker process writes its pair's report itself; here only the folder is made.
  PairReports reports(o, o.isolate ? std::vector<std::pair<ListPair, std::string>>{} : todo);
  const std::vector<PairJob> jobs = group_jobs(todo, !o.report_dir.empty());
  Progress progress(todo, o.quiet || todo.empty() ? BatchProgressCallback() : o.progress);
  const int concurrent = std::max(1, std::min<int>(o.jobs, static_cast<int>(jobs.size())));
  const int total_threads = o.threads > 0 ? o.threads : omp_get_num_procs();
  // Each job gets its share of the threads, passed to every metric explicitly (a metric's own
  // concurrent tasks then share that count too).
  const int job_threads = std::max(1, total_threads / concurrent);
  const BatchOptions per_job = job_options(o, job_threads);
  const std::string settings_field = "," + csv_field(settings);
  std::atomic<std::size_t> next{0};
  std::mutex write_error_mutex;
  std::string write_error;  // the first row that could not be written
  const RowDone done = [&](const std::string& row, bool failed) {
    try {
      out.write_line(row + settings_field);
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(write_error_mutex);
      if (write_error.empty()) write_error = e.what();
      next = jobs.size();  // no job starts after a failed write
      return;
    }
    progress.done_one(row, failed);
  };
  std::atomic<bool> workers_ok{true};
  auto worker = [&] {
    if (!o.isolate) omp_set_num_threads(job_threads);
    WorkerProcess process(worker_args(o));  // started by its first job
    for (std::size_t i = next++; i < jobs.size(); i = next++) {
      if (!o.isolate) {
        score_here(jobs[i], per_job, reports, done);
      } else if (!score_in_worker(jobs[i], process, job_threads, o, done)) {
        workers_ok = false;
      }
    }
  };
  std::vector<std::thread> threads;
  for (int j = 1; j < concurrent; ++j) threads.emplace_back(worker);
  worker();
  for (auto& t : threads) t.join();
  if (!write_error.empty()) throw InputError(write_error);
  reports.write_index(o.output);
  for (const std::string& e : reports.errors()) std::cerr << "qm3d: error: report: " << e << "\n";
  return {progress.failed(), reports.errors().empty() && workers_ok};
}

// The exit code: 2 while any row of the results (this run's or an earlier one's) records an
// error, or a report failed.
int finish(const BatchOptions& o, const ScoringSummary& run) {
  std::error_code ec;
  const std::size_t errors = std::filesystem::is_regular_file(o.output, ec)
                                 ? count_error_rows(read_file_bytes(o.output))
                                 : run.failed_rows;  // a pipe or device: this run's rows
  if (errors > 0 && !o.quiet) {
    std::cerr << "batch: " << errors << " rows of " << o.output.string()
              << " record an error; `--resume --retry-failed` scores them again\n";
  }
  return errors == 0 && run.reports_ok ? 0 : 2;
}

}  // namespace

std::string progress_counts(const BatchProgress& p) {
  const std::string pairs =
      std::to_string(p.pairs_done) + "/" + std::to_string(p.pairs_total) + " pairs";
  if (p.pairs_total == p.rows_total) return pairs;
  return std::to_string(p.rows_done) + "/" + std::to_string(p.rows_total) + " rows, " + pairs;
}

std::filesystem::path resolve(const std::filesystem::path& list, const std::string& p) {
  const std::filesystem::path path(p);
  return path.is_absolute() ? path : list.parent_path() / path;
}

std::vector<std::string> batch_metrics(const ListPair& pair, const std::filesystem::path& list) {
  if (pair.metric != "compare" && pair.metric != "auto") return {pair.metric};
  try {
    const Input ref = default_registry().read(resolve(list, pair.reference));
    const Input dist = default_registry().read(resolve(list, pair.distorted));
    std::vector<std::string> names;
    for (const MetricSpec* m : metrics_for(pair.metric, ref, dist)) names.push_back(m->name);
    return names;
  } catch (const Error&) {
    return {pair.metric};
  }
}

namespace {

// BatchOptions::value_names of a list.
std::vector<std::string> list_value_names(const std::vector<ListPair>& pairs) {
  std::vector<const MetricSpec*> specs;
  for (const ListPair& p : pairs) {
    if (p.metric == "compare") {
      // Every metric's value columns, as qm3d.dask's fixed schema has them.
      for (const MetricSpec& s : default_registry().metrics()) specs.push_back(&s);
    } else if (const MetricSpec* s = default_registry().find(p.metric)) {
      specs.push_back(s);
    }
  }
  return csv_value_names(specs);
}

// Each pair's texture maps; a pair listed twice with other maps is an error (its rows are keyed
// by reference, distorted and metric).
std::map<std::pair<std::string, std::string>, std::pair<std::string, std::string>> list_textures(
    const std::vector<ListPair>& pairs, const std::filesystem::path& list) {
  std::map<std::pair<std::string, std::string>, std::pair<std::string, std::string>> out;
  for (const ListPair& p : pairs) {
    const std::pair<std::string, std::string> maps{p.ref_texture, p.dist_texture};
    const auto [at, added] = out.emplace(std::pair{p.reference, p.distorted}, maps);
    if (!added && at->second != maps) {
      throw FormatError(list.string() + ": " + p.reference + ", " + p.distorted +
                        " is listed with different texture maps");
    }
  }
  return out;
}

}  // namespace

int run_batch(const BatchOptions& options) {
  std::vector<ListPair> pairs =
      parse_pair_list(read_file_bytes(options.list, kMaxTableBytes), options.list.string());
  BatchOptions o = options;
  o.value_names = list_value_names(pairs);
  o.textures = list_textures(pairs, o.list);
  if (o.shard) pairs = select_shard(pairs, *o.shard, [&](const ListPair& p) {
    return input_bytes(resolve(o.list, p.reference)) + input_bytes(resolve(o.list, p.distorted));
  });
  refuse_input_as_output(o, pairs);
  if (!o.report_dir.empty()) make_report_dir(o.report_dir);  // before the output is touched
  if (o.retry_failed && !o.resume) throw std::invalid_argument("--retry-failed needs --resume");
  const bool exists = std::filesystem::exists(o.output);
  if (exists && !o.resume && !o.overwrite) {
    throw InputError(o.output.string() +
                     ": already exists (use --resume to continue it or --overwrite to replace it)");
  }
  const std::string settings = batch_settings(o.request);
  LockedResults out(o.output);
  std::set<RowKey> done = prepare_output(out, o, settings, exists);
  std::vector<std::pair<ListPair, std::string>> todo;
  std::vector<RowKey> order;  // (pair, metric) rows the list asks for, in its order
  for (const ListPair& p : pairs) {
    for (const std::string& metric : batch_metrics(p, o.list)) {
      order.emplace_back(p.reference, p.distorted, metric);
      if (done.insert(order.back()).second) todo.emplace_back(p, metric);
    }
  }
  if (!o.quiet && todo.size() < order.size()) {
    std::cerr << "batch: " << order.size() - todo.size() << " pairs already done, " << todo.size()
              << " to go\n";
  }
  const ScoringSummary run = score_jobs(o, todo, out, settings);
  // The final file for reading: list order, the value columns of the metrics it has. Shards
  // keep the full header, which `qm3d merge` requires of every shard.
  if (out.is_regular() && !o.shard) {
    out.replace(tidy_results(read_file_bytes(o.output), order, o.value_names));
  }
  return finish(o, run);
}

namespace {

// One job of a worker: its rows on stdout as they are scored, then the end line.
void run_worker_job(const BatchOptions& o, const std::string& line) {
  const auto f = csv_split(line);
  if (f.size() < 4 || f[0].empty() || f[0].size() > 6 ||
      f[0].find_first_not_of("0123456789") != std::string::npos) {
    throw std::invalid_argument("--batch-worker: an internal option of qm3d batch");
  }
  const int threads = std::max(1, std::stoi(f[0]));
  const PairJob job{{f[1], f[2], ""}, {f.begin() + 3, f.end()}};
  std::vector<std::pair<ListPair, std::string>> todo;
  for (const std::string& m : job.metrics) todo.emplace_back(job.pair, m);
  omp_set_num_threads(threads);
  PairReports reports(o, todo);
  test_fault(job.pair);
  score_here(job, job_options(o, threads), reports, [](const std::string& row, bool) {
    std::cout << row << "\n" << std::flush;
  });
  for (const std::string& e : reports.errors()) std::cerr << "qm3d: error: report: " << e << "\n";
  std::cout << kJobEnd << (reports.errors().empty() ? "" : " report-failed") << "\n" << std::flush;
}

}  // namespace

int run_batch_worker(const BatchOptions& options) {
  BatchOptions o = options;
  const std::vector<ListPair> pairs =
      parse_pair_list(read_file_bytes(options.list, kMaxTableBytes), options.list.string());
  o.value_names = list_value_names(pairs);
  o.textures = list_textures(pairs, o.list);
  // A worker outliving its batch (killed with SIGKILL) would go on scoring for nobody.
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  std::string line;
  while (std::getline(std::cin, line)) run_worker_job(o, line);
  return 0;
}

}  // namespace qm3d::study
