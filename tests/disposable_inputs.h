// Copies of a metric's two inputs that its RunOptions::inputs_done callback empties, for the
// tests that check a metric reads its inputs no more once it has said so.
#pragma once

#include <functional>

namespace qm3d::test {

/// `reference` and `distorted` are the metric's inputs; callback() counts its calls in `calls`
/// and empties both, so that any later read changes the result or fails under the sanitizers.
/// The object must outlive the callback's use.
template <typename Data>
struct DisposableInputs {
  Data reference, distorted;
  int calls = 0;
  std::function<void()> callback() {
    return [this] {
      ++calls;
      reference = Data{};
      distorted = Data{};
    };
  }
};

}  // namespace qm3d::test
