// Scoring a batch pair in a process of its own, so that a fatal fault of that pair (a signal, an
// abort, memory exhaustion, a hang) ends only that process and becomes the pair's error row.
// The worker is this executable again (/proc/self/exe: never a bare fork() of a process whose
// OpenMP runtime may already have threads, which libgomp does not survive).
#pragma once

#include <string>
#include <vector>

namespace qm3d::app {

/// What a worker process left: its standard output and how it ended.
struct WorkerOutcome {
  std::string output;       ///< everything it wrote on stdout
  int wait_status = 0;      ///< as waitpid(2) reports it
  bool timed_out = false;   ///< killed (SIGKILL) after the time limit
  std::string spawn_error;  ///< non-empty when it could not be started
};

/// Runs /proc/self/exe with `args` (args[0] is the program name it sees), stdin /dev/null,
/// stdout collected, stderr shared with this process; kills it after `timeout_s` seconds when
/// positive. Safe to call from several threads at once. Never throws for the worker's faults.
WorkerOutcome run_worker(const std::vector<std::string>& args, double timeout_s);

/// Why a worker gave no row, for the error column: "crashed: signal 11 (SIGSEGV)", "timed out
/// after 5 s (--pair-timeout) and was killed", ...; "worker ended without a result" when it
/// exited normally.
std::string describe_worker_end(const WorkerOutcome& outcome, double timeout_s);

}  // namespace qm3d::app
