// Scoring batch pairs in a process apart, so that a fatal fault of a pair (a signal, an abort,
// memory exhaustion, a hang) ends only that process and becomes the pair's error row. The
// worker is this executable again (/proc/self/exe: never a bare fork() of a process whose
// OpenMP runtime may already have threads, which libgomp does not survive). One worker scores
// job after job (the start of a process and the tables it loads are paid once, not per pair)
// until it dies; the next job then starts a new one.
#pragma once

#include <sys/types.h>

#include <functional>
#include <string>
#include <vector>

namespace qm3d::study {

/// The line a worker writes after the output of each job: "<kJobEnd>" or "<kJobEnd> STATUS".
inline constexpr const char* kJobEnd = "#qm3d-job-end";

/// How one job ended: when it did not finish, how the worker ended.
struct JobOutcome {
  bool finished = false;           ///< the worker wrote the end line
  std::string end_status;          ///< what followed kJobEnd on the end line ("" = ok)
  int wait_status = 0;             ///< when not finished: as waitpid(2) reports the worker
  bool timed_out = false;          ///< when not finished: killed (SIGKILL) after the limit
  std::string spawn_error;         ///< when not finished: the worker could not be started
};

/// The longest time limit a job can have, 1e9 s (31 years): a longer one (inf included) is no
/// limit. The deadline is a steady_clock time point in int64 nanoseconds, which overflow from
/// 9.2e9 s on (--pair-timeout 1e10 would otherwise have every job time out at once).
inline constexpr double kMaxJobTimeoutS = 1e9;

/// A worker process: /proc/self/exe with `args` (args[0] is the program name it sees), jobs on
/// its stdin, one line each, its output on its stdout; stderr shared with this process. Used by
/// one thread at a time; several may exist at once.
class WorkerProcess {
 public:
  explicit WorkerProcess(std::vector<std::string> args) : args_(std::move(args)) {}
  ~WorkerProcess();  ///< closes its stdin (it ends) and waits for it
  WorkerProcess(const WorkerProcess&) = delete;
  WorkerProcess& operator=(const WorkerProcess&) = delete;

  /// Sends `job` (one line), starting the worker first when none runs, and gives each complete
  /// line of its output to `line` as it arrives, up to the end line; kills the worker when that
  /// takes over `timeout_s` seconds (positive; 0, NaN or over kMaxJobTimeoutS: no limit). Never
  /// throws for the worker's faults: they are in the outcome.
  JobOutcome run(const std::string& job, double timeout_s,
                 const std::function<void(const std::string&)>& line);

 private:
  bool start(std::string& error);
  int reap();  // closes the pipes, waits for the worker; its wait status

  std::vector<std::string> args_;
  pid_t pid_ = -1;
  int to_worker_ = -1, from_worker_ = -1;
  std::string buffer_;  // read but not yet returned
};

/// Why a job gave no row, for the error column: "crashed: signal 11 (SIGSEGV)", "timed out
/// after 5 s (--pair-timeout) and was killed", ...
std::string describe_worker_end(const JobOutcome& outcome, double timeout_s);

}  // namespace qm3d::study
