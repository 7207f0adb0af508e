// Progress of a long computation, for callers that show it (the qm3d tool on a terminal).
//
// Example:
//   CmdmOptions o;
//   o.progress = [](const std::string& stage, double fraction) {
//     std::cerr << "\r" << stage << " " << int(100 * fraction) << "%";
//   };
#pragma once

#include <algorithm>
#include <functional>
#include <string>
#include <utility>

namespace qm3d {

/// Told how far a computation has got: `stage` says what runs now (e.g. "dist→ref, scale 2/3"),
/// `fraction` the part already done, in [0, 1] and never decreasing; the last call has fraction 1.
/// Called from the thread that called the metric, between stages, never from a parallel loop.
using ProgressCallback = std::function<void(const std::string& stage, double fraction)>;

/// Splits a computation into a known number of steps of about equal cost and reports each one
/// to an optional callback (nothing happens when it is empty).
class ProgressSteps {
 public:
  ProgressSteps(ProgressCallback callback, int total_steps)
      : callback_(std::move(callback)), total_(std::max(total_steps, 1)) {}

  /// `stage`, worth `steps` steps, starts: reports the steps done so far.
  void begin(const std::string& stage, int steps = 1) {
    if (callback_) callback_(stage, static_cast<double>(std::min(started_, total_)) / total_);
    started_ += steps;
  }
  /// All steps are done: reports fraction 1.
  void finish() {
    if (callback_) callback_("done", 1.0);
  }

 private:
  ProgressCallback callback_;
  int total_;
  int started_ = 0;
};

}  // namespace qm3d
