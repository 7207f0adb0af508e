// Long calls that Ctrl-C interrupts. A metric call runs on a worker thread while the calling
// thread waits with the GIL released and looks for signals every kSignalPollInterval, so a
// KeyboardInterrupt reaches Python within a fraction of a second whatever the metric is doing.
// The worker is then told to stop: it throws CallCancelled at its next progress report (between
// stages, on its own thread, where unwinding is safe) and frees what it holds. It owns copies of
// the inputs' handles, so nothing it uses is freed under it by Python.
#pragma once

#include <pybind11/pybind11.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

namespace qm3d::python {

/// Thrown inside a worker whose caller was interrupted; never reaches Python.
struct CallCancelled : std::exception {
  const char* what() const noexcept override { return "cancelled"; }
};

/// How often the waiting thread checks for signals (KeyboardInterrupt latency).
constexpr std::chrono::milliseconds kSignalPollInterval{50};

/// The workers still running after their callers were interrupted; waited for at exit.
class AbandonedWorkers {
 public:
  static AbandonedWorkers& instance() {
    static AbandonedWorkers* workers = new AbandonedWorkers;  // never destroyed: workers use it
    return *workers;
  }
  void started() {
    std::lock_guard<std::mutex> lock(mutex_);
    ++running_;
  }
  void finished() {
    std::lock_guard<std::mutex> lock(mutex_);
    --running_;
    changed_.notify_all();
  }
  /// Blocks until every worker has stopped (they stop at their next stage boundary).
  void wait_all() {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] { return running_ == 0; });
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  int running_ = 0;
};

/// The state shared by the caller and its worker.
template <typename Result>
struct CallState {
  std::mutex mutex;
  std::condition_variable finished;
  bool done = false;
  std::optional<Result> result;
  std::exception_ptr error;
  std::atomic<bool> cancelled{false};
};

/// Runs `body(cancelled)` on a worker thread; the caller holds the GIL on entry and on return.
/// `body` should test `cancelled` at its stage boundaries (throwing CallCancelled). On a signal
/// whose Python handler raises (Ctrl-C: KeyboardInterrupt) the worker is cancelled and the
/// exception is raised at once, without waiting for the worker.
template <typename Result>
Result call_interruptibly(std::function<Result(const std::atomic<bool>& cancelled)> body) {
  auto state = std::make_shared<CallState<Result>>();
  AbandonedWorkers::instance().started();
  std::thread([state, body = std::move(body)]() mutable {
    {
      // Everything the call holds (the user's callback among it) is destroyed in this scope,
      // before finished(): once the last worker has finished, the interpreter may shut down.
      auto call = std::move(body);
      try {
        Result r = call(state->cancelled);
        std::lock_guard<std::mutex> lock(state->mutex);
        state->result.emplace(std::move(r));
      } catch (...) {
        std::lock_guard<std::mutex> lock(state->mutex);
        state->error = std::current_exception();
      }
    }
    {
      std::lock_guard<std::mutex> lock(state->mutex);
      state->done = true;
      if (state->cancelled) {  // the caller has gone: nothing it would have read outlives us
        state->error = nullptr;
        state->result.reset();
      }
    }
    state->finished.notify_all();
    AbandonedWorkers::instance().finished();
  }).detach();
  for (;;) {
    {
      pybind11::gil_scoped_release release;
      std::unique_lock<std::mutex> lock(state->mutex);
      if (state->finished.wait_for(lock, kSignalPollInterval, [&] { return state->done; })) break;
    }
    if (PyErr_CheckSignals() != 0) {
      std::lock_guard<std::mutex> lock(state->mutex);
      state->cancelled = true;
      if (state->done) {  // finished meanwhile: its outcome is dropped here, with the GIL
        state->error = nullptr;
        state->result.reset();
      }
      throw pybind11::error_already_set();
    }
  }
  if (state->error) std::rethrow_exception(state->error);
  return std::move(*state->result);
}

}  // namespace qm3d::python
