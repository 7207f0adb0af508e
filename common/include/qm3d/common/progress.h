// Progress of a long computation, for callers that show it (the qm3d tool on a terminal).
//
// Example:
//   CmdmOptions o;
//   o.progress = [](const std::string& stage, double fraction) {
//     std::cerr << "\r" << stage << " " << int(100 * fraction) << "%";
//   };
//
// Inside a metric, a long parallel loop reports how far it has got:
//   ProgressSteps steps(run.progress, 3);
//   steps.begin("features");
//   LoopProgress loop(&steps, n);          // n items in this stage
//   #pragma omp parallel for schedule(dynamic, 256)
//   for (long i = 0; i < n; ++i) { ...; loop.add(1); }   // any thread; only the caller reports
//   loop.finish();                         // rethrows what the callback threw (e.g. cancelled)
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <exception>
#include <functional>
#include <string>
#include <thread>
#include <utility>

namespace qm3d {

/// Told how far a computation has got: `stage` says what runs now (e.g. "dist→ref, scale 2/3"),
/// `fraction` the part already done, in [0, 1] and never decreasing; the last call has fraction 1.
/// Called from the thread that called the metric, between stages and, in long stages, from
/// inside their loops (LoopProgress), never from another thread.
using ProgressCallback = std::function<void(const std::string& stage, double fraction)>;

/// Splits a computation into a known number of steps of about equal cost and reports each one
/// to an optional callback (nothing happens when it is empty), and how far the running step
/// has got (within).
class ProgressSteps {
 public:
  ProgressSteps(ProgressCallback callback, int total_steps)
      : callback_(std::move(callback)), total_(std::max(total_steps, 1)) {}

  /// `stage`, worth `steps` steps, starts: reports the steps done so far.
  void begin(const std::string& stage, int steps = 1) {
    stage_ = stage;
    stage_start_ = static_cast<double>(std::min(started_, total_)) / total_;
    started_ += steps;
    stage_end_ = static_cast<double>(std::min(started_, total_)) / total_;
    report(stage_start_);
  }
  /// The running stage is `fraction` (0..1) done: reports its share of the whole. Only from the
  /// thread that called the metric.
  void within(double fraction) {
    report(stage_start_ + (stage_end_ - stage_start_) * std::clamp(fraction, 0.0, 1.0));
  }
  /// All steps are done: reports fraction 1.
  void finish() {
    if (callback_) callback_("done", 1.0);
  }
  bool active() const { return static_cast<bool>(callback_); }

 private:
  void report(double fraction) {
    last_ = std::max(last_, fraction);  // never decreasing
    if (callback_) callback_(stage_, last_);
  }

  ProgressCallback callback_;
  int total_;
  int started_ = 0;
  std::string stage_;
  double stage_start_ = 0, stage_end_ = 0, last_ = 0;
};

/// Counts the items a (parallel) loop of the running stage has finished, from any thread, and
/// reports the stage's progress from the thread that created it (the metric's caller; with
/// OpenMP, the team's master thread): at each further hundredth of the items, or
/// kLoopProgressInterval after the last report. Results do not depend on it.
class LoopProgress {
 public:
  /// Longest time between two reports while the creating thread keeps adding.
  static constexpr std::chrono::milliseconds kInterval{250};
  static constexpr std::size_t kReportsPerStage = 100;

  /// `steps` may be null or silent: add() then only counts.
  LoopProgress(ProgressSteps* steps, std::size_t total)
      : steps_(steps && steps->active() ? steps : nullptr),
        total_(std::max<std::size_t>(total, 1)),
        owner_(std::this_thread::get_id()),
        last_time_(std::chrono::steady_clock::now()) {}

  /// `n` more items are done (any thread; cheap when no one listens).
  void add(std::size_t n = 1) {
    if (!steps_) return;
    const std::size_t done = done_.fetch_add(n, std::memory_order_relaxed) + n;
    if (std::this_thread::get_id() != owner_) return;
    const std::size_t hundredth = done * kReportsPerStage / total_;
    const auto now = std::chrono::steady_clock::now();
    if (hundredth <= last_hundredth_ && now - last_time_ < kInterval) return;
    last_hundredth_ = hundredth;
    last_time_ = now;
    if (error_) return;
    // The callback may throw (a cancelled call, a Python callback's exception): never out of
    // the parallel loop (std::terminate); kept for finish().
    try {
      steps_->within(static_cast<double>(std::min(done, total_)) / static_cast<double>(total_));
    } catch (...) {
      error_ = std::current_exception();
    }
  }
  /// After the loop, outside any parallel region: rethrows what the callback threw.
  void finish() {
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  }

 private:
  ProgressSteps* steps_;
  std::size_t total_;
  std::thread::id owner_;
  std::atomic<std::size_t> done_{0};
  std::size_t last_hundredth_ = 0;
  std::chrono::steady_clock::time_point last_time_;
  std::exception_ptr error_;  ///< what the callback threw (read and written by the owner only)
};

}  // namespace qm3d
