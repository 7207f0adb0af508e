#include "batch.h"

#include <fcntl.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iostream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>

#include "commands.h"
#include "progress_display.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/result_io.h"

namespace qm3d::app {
namespace {

using Key = std::tuple<std::string, std::string, std::string>;

// Keys of the rows already in the results; drops a trailing partial line left by a crash.
std::set<Key> finished_pairs(const std::filesystem::path& output) {
  std::string text = read_file_bytes(output);
  const auto last_newline = text.find_last_of('\n');
  const std::size_t complete = last_newline == std::string::npos ? 0 : last_newline + 1;
  if (complete != text.size()) {
    std::filesystem::resize_file(output, complete);
    text.resize(complete);
  }
  std::set<Key> done;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    const auto f = csv_split(line);
    if (f.size() >= 3 && f[0] != "reference") done.emplace(f[0], f[1], f[2]);
  }
  return done;
}

// Appends one line with a single write(2), so a kill never leaves half a row.
class RowWriter {
 public:
  explicit RowWriter(const std::filesystem::path& path) : path_(path) {
    fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (fd_ < 0) throw InputError(path.string() + ": cannot open for writing");
  }
  ~RowWriter() {
    if (fd_ >= 0) ::close(fd_);
  }
  void write_line(const std::string& row) {
    const std::string line = row + "\n";
    std::lock_guard<std::mutex> lock(mutex_);
    const ssize_t n = ::write(fd_, line.data(), line.size());
    if (n != static_cast<ssize_t>(line.size())) {
      throw InputError(path_.string() + ": write failed (disk full?)");
    }
  }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
  std::mutex mutex_;
};

class Progress {
 public:
  Progress(std::size_t total, bool quiet)
      : total_(total), quiet_(quiet), tty_(stderr_is_terminal()),
        start_(std::chrono::steady_clock::now()), last_(start_) {}

  void done_one(bool failed) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++done_;
    failed_ += failed ? 1 : 0;
    if (quiet_) return;
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double eta = elapsed / done_ * (total_ - done_);
    if (tty_) {
      const int width = 30;
      const int filled = static_cast<int>(width * done_ / total_);
      std::cerr << "\r[" << std::string(filled, '#') << std::string(width - filled, '.') << "] "
                << done_ << "/" << total_ << " (" << failed_ << " failed)  ETA "
                << format_duration(eta) << "   " << std::flush;
      if (done_ == total_) std::cerr << "\n";
    } else if (done_ == total_ || now - last_ > std::chrono::seconds(10)) {
      std::cerr << "batch: " << done_ << "/" << total_ << " pairs done (" << failed_
                << " failed), elapsed " << format_duration(elapsed) << ", ETA "
                << format_duration(eta) << "\n";
      last_ = now;
    }
  }
  std::size_t failed() const { return failed_; }

 private:
  std::size_t total_, done_ = 0, failed_ = 0;
  bool quiet_, tty_;
  std::chrono::steady_clock::time_point start_, last_;
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

// Scores one pair; never throws (a failure becomes the row's error).
ScoredRow score_pair(const ListPair& pair, const std::string& metric, const BatchOptions& o) {
  const auto ref = resolve(o.list, pair.reference), dist = resolve(o.list, pair.distorted);
  try {
    const Input r = registry().read(ref), d = registry().read(dist);
    const auto specs = metrics_for(metric, r, d);
    ScoreRequest request = o.request;
    request.release_inputs = o.report_dir.empty();  // a report reads both inputs
    MetricResult result = score(*specs.front(), r, d, request);
    result.provenance.reference = pair.reference;
    result.provenance.distorted = pair.distorted;
    ScoredRow s{csv_row(result), false, specs.front(), std::nullopt, r, d};
    if (!o.report_dir.empty()) s.result = std::move(result);
    return s;
  } catch (const std::exception& e) {
    return {csv_error_row(pair.reference, pair.distorted, metric, e.what()), true, nullptr,
            std::nullopt, std::nullopt, std::nullopt};
  }
}

// The reports of --report-dir: a pair's results are gathered until its last row of this run is
// scored, then its report is written (by the worker that scored that row).
class PairReports {
 public:
  PairReports(const BatchOptions& o, const std::vector<std::pair<ListPair, std::string>>& todo)
      : o_(o) {
    if (o.report_dir.empty()) return;
    std::error_code ec;
    std::filesystem::create_directories(o.report_dir, ec);
    if (ec || !std::filesystem::is_directory(o.report_dir)) {
      throw InputError(o.report_dir.string() + ": cannot create the report folder (--report-dir)" +
                       (ec ? ": " + ec.message() : std::string()));
    }
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
    std::vector<IndexRow> rows;
    std::istringstream in(read_file_bytes(results));
    std::string line;
    while (std::getline(in, line)) {
      const auto f = csv_split(line);
      if (f.size() < 6 || f[0] == "reference") continue;
      IndexRow r{f[0], f[1], f[2], std::nullopt, f[5], ""};
      if (f[4] == "ok" && !f[3].empty()) r.score = std::stod(f[3]);
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

}  // namespace

std::filesystem::path resolve(const std::filesystem::path& list, const std::string& p) {
  const std::filesystem::path path(p);
  return path.is_absolute() ? path : list.parent_path() / path;
}

std::vector<std::string> batch_metrics(const ListPair& pair, const std::filesystem::path& list) {
  if (pair.metric != "compare" && pair.metric != "auto") return {pair.metric};
  try {
    const Input ref = registry().read(resolve(list, pair.reference));
    const Input dist = registry().read(resolve(list, pair.distorted));
    std::vector<std::string> names;
    for (const MetricSpec* m : metrics_for(pair.metric, ref, dist)) names.push_back(m->name);
    return names;
  } catch (const Error&) {
    return {pair.metric};
  }
}

int run_batch(const BatchOptions& o) {
  std::vector<ListPair> pairs =
      parse_pair_list(read_file_bytes(o.list), o.list.string());
  if (o.shard) pairs = select_shard(pairs, *o.shard, [&](const ListPair& p) {
    return input_bytes(resolve(o.list, p.reference)) + input_bytes(resolve(o.list, p.distorted));
  });
  std::set<Key> done;
  const bool exists = std::filesystem::exists(o.output);
  if (exists && o.resume) {
    done = finished_pairs(o.output);
  } else if (exists && !o.overwrite) {
    throw InputError(o.output.string() +
                     ": already exists (use --resume to continue it or --overwrite to replace it)");
  } else if (exists) {
    std::filesystem::remove(o.output);
  }
  std::vector<std::pair<ListPair, std::string>> todo;
  std::size_t rows = 0;  // (pair, metric) rows the list asks for
  for (const ListPair& p : pairs) {
    for (const std::string& metric : batch_metrics(p, o.list)) {
      ++rows;
      if (done.insert({p.reference, p.distorted, metric}).second) todo.emplace_back(p, metric);
    }
  }
  PairReports reports(o, todo);
  RowWriter writer(o.output);
  if (!exists || !o.resume || std::filesystem::file_size(o.output) == 0) {
    writer.write_line(csv_header());
  }
  if (!o.quiet && todo.size() < rows) {
    std::cerr << "batch: " << rows - todo.size() << " pairs already done, "
              << todo.size() << " to go\n";
  }
  Progress progress(std::max<std::size_t>(todo.size(), 1), o.quiet || todo.empty());
  const int jobs = std::max(1, std::min<int>(o.jobs, static_cast<int>(todo.size())));
  const int total_threads = o.threads > 0 ? o.threads : omp_get_num_procs();
  std::atomic<std::size_t> next{0};
  // Each job gets its share of the threads, passed to every metric explicitly (a metric's own
  // concurrent tasks then share that count too).
  BatchOptions per_job = o;
  const int job_threads = std::max(1, total_threads / jobs);
  per_job.request.run.threads = job_threads;
  per_job.request.keep_per_element = !o.report_dir.empty();
  auto worker = [&] {
    omp_set_num_threads(job_threads);
    for (std::size_t i = next++; i < todo.size(); i = next++) {
      ScoredRow s = score_pair(todo[i].first, todo[i].second, per_job);
      writer.write_line(s.row);
      const bool failed = s.failed;
      reports.add(todo[i].first, std::move(s));
      progress.done_one(failed);
    }
  };
  std::vector<std::thread> threads;
  for (int j = 1; j < jobs; ++j) threads.emplace_back(worker);
  worker();
  for (auto& t : threads) t.join();
  reports.write_index(o.output);
  for (const std::string& e : reports.errors()) std::cerr << "qm3d: error: report: " << e << "\n";
  return progress.failed() == 0 && reports.errors().empty() ? 0 : 2;
}

}  // namespace qm3d::app
