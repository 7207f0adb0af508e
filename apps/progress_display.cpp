#include "progress_display.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <iomanip>
#include <iostream>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>

namespace qm3d::app {
namespace {

using Clock = std::chrono::steady_clock;

/// How often a line on a terminal is rewritten while the metric reports nothing (the clock and
/// the estimate keep moving), and the shortest time between two rewrites by the metric.
constexpr std::chrono::milliseconds kTick{500};
constexpr std::chrono::milliseconds kMinRewrite{100};
/// No estimate before this share of the work or this many seconds (too noisy).
constexpr double kEstimateFromFraction = 0.02;
constexpr double kEstimateFromSeconds = 1.0;

/// The progress of one metric on stderr; on a terminal, a ticker thread rewrites the line every
/// kTick until the metric is done or the display is destroyed (also when the metric fails).
class Display {
 public:
  Display(std::string metric, bool in_place) : metric_(std::move(metric)), in_place_(in_place) {}
  ~Display() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (in_place_ && started_ && !stop_) std::cerr << "\r\033[K" << std::flush;  // not done
      stop_ = true;
    }
    wake_.notify_all();
    if (ticker_.joinable()) ticker_.join();
  }
  Display(const Display&) = delete;
  Display& operator=(const Display&) = delete;

  void report(const std::string& stage, double fraction) {
    std::unique_lock<std::mutex> lock(mutex_);
    const auto now = Clock::now();
    if (fraction == 0 && !started_) {  // the metric's first stage (each run starts at 0)
      start_ = now;
      started_ = true;
    }
    const bool new_stage = stage != stage_;
    stage_ = stage;
    fraction_ = fraction;
    if (!in_place_) {
      if (new_stage) std::cerr << "qm3d: " << line(now) << "\n";  // done included
      return;
    }
    if (fraction >= 1) {
      stop_ = true;
      std::cerr << "\r\033[K" << std::flush;  // done: leave the terminal as it was
      lock.unlock();
      wake_.notify_all();
      return;
    }
    if (new_stage || now - written_ >= kMinRewrite) write(now);
    if (!ticker_.joinable() && !stop_) ticker_ = std::thread([this] { tick(); });
  }

 private:
  std::string line(Clock::time_point now) const {
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    std::ostringstream o;
    o << metric_ << ": " << std::setw(3) << std::lround(100 * fraction_) << "%  " << stage_ << "  ("
      << format_duration(elapsed);
    if (fraction_ >= kEstimateFromFraction && elapsed >= kEstimateFromSeconds) {
      o << ", ~" << format_duration(elapsed * (1 - fraction_) / fraction_) << " left";
    }
    o << ")";
    return o.str();
  }
  void write(Clock::time_point now) {                          // mutex_ held
    std::cerr << "\r" << line(now) << "\033[K" << std::flush;  // \033[K: erase to line end
    written_ = now;
  }
  void tick() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!wake_.wait_for(lock, kTick, [this] { return stop_; })) {
      if (Clock::now() - written_ >= kTick) write(Clock::now());
    }
  }

  const std::string metric_;
  const bool in_place_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::thread ticker_;
  bool started_ = false, stop_ = false;
  Clock::time_point start_{}, written_{};
  std::string stage_;
  double fraction_ = 0;
};

}  // namespace

std::string format_duration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  std::ostringstream o;
  const long t = std::lround(s);
  if (t >= 3600) o << t / 3600 << "h";
  if (t >= 60) o << (t / 60) % 60 << "m";
  o << t % 60 << "s";
  return o.str();
}

bool stderr_is_terminal() { return ::isatty(STDERR_FILENO) == 1; }

void clear_progress_line() {
  if (stderr_is_terminal()) std::cerr << "\r\033[K";
}

ProgressCallback stderr_progress(const std::string& metric, bool in_place) {
  auto display = std::make_shared<Display>(metric, in_place);
  return [display](const std::string& stage, double fraction) { display->report(stage, fraction); };
}

study::BatchProgressCallback stderr_batch_progress() {
  constexpr double kLinePeriodS = 10;  // without a terminal: a line at most this often
  constexpr int kBarWidth = 30;
  const bool tty = stderr_is_terminal();
  auto last_line_s = std::make_shared<double>(0.0);  // elapsed time of the last line
  return [tty, last_line_s](const study::BatchProgress& p) {
    const bool end = p.rows_done == p.rows_total;
    if (tty) {
      const int filled = static_cast<int>(kBarWidth * p.rows_done / p.rows_total);
      std::cerr << "\r[" << std::string(filled, '#') << std::string(kBarWidth - filled, '.')
                << "] " << study::progress_counts(p) << " (" << p.failed << " failed)  ETA "
                << format_duration(p.eta_s) << "   " << std::flush;
      if (end) std::cerr << "\n";
    } else if (end || p.elapsed_s - *last_line_s > kLinePeriodS) {
      std::cerr << "batch: " << study::progress_counts(p) << " done (" << p.failed
                << " failed), elapsed " << format_duration(p.elapsed_s) << ", ETA "
                << format_duration(p.eta_s) << "\n";
      *last_line_s = p.elapsed_s;
    }
  };
}

}  // namespace qm3d::app
