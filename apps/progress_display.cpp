#include "progress_display.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace qm3d::app {

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
  using Clock = std::chrono::steady_clock;
  return [metric, in_place, start = Clock::time_point{}](const std::string& stage,
                                                         double fraction) mutable {
    const auto now = Clock::now();
    if (fraction == 0) start = now;  // the metric's first stage (each run starts at 0)
    const double elapsed = std::chrono::duration<double>(now - start).count();
    std::ostringstream line;
    line << metric << ": " << std::setw(3) << std::lround(100 * fraction) << "%  " << stage
         << "  (" << format_duration(elapsed) << ")";
    if (!in_place) {
      std::cerr << "qm3d: " << line.str() << "\n";
    } else if (fraction < 1) {
      std::cerr << "\r" << line.str() << "\033[K" << std::flush;  // \033[K: erase to line end
    } else {
      std::cerr << "\r\033[K" << std::flush;  // done: leave the terminal as it was
    }
  };
}

}  // namespace qm3d::app
