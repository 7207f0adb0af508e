// Records what a metric reports through its ProgressCallback, for the tests.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "qm3d/common/progress.h"

namespace qm3d::test {

using ProgressCalls = std::vector<std::pair<std::string, double>>;

struct ProgressRecorder {
  ProgressCalls calls;
  /// A callback appending (stage, fraction) to `calls`; the recorder must outlive its use.
  ProgressCallback callback() {
    return [this](const std::string& stage, double f) { calls.emplace_back(stage, f); };
  }
  /// The first call of each stage (the calls made between stages; a long stage also reports
  /// from inside its loops, LoopProgress).
  ProgressCalls stage_starts() const {
    ProgressCalls out;
    for (const auto& c : calls) {
      if (out.empty() || out.back().first != c.first) out.push_back(c);
    }
    return out;
  }
  /// The calls made from inside `stage` (after its first).
  std::vector<double> within(const std::string& stage) const {
    std::vector<double> out;
    bool first = true;
    for (const auto& c : calls) {
      if (c.first != stage) continue;
      if (!first) out.push_back(c.second);
      first = false;
    }
    return out;
  }
};

}  // namespace qm3d::test
