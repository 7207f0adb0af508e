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
};

}  // namespace qm3d::test
