#include "pair_process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>

#include "qm3d/common/result_io.h"

extern char** environ;

namespace qm3d::study {
namespace {

using Clock = std::chrono::steady_clock;

// Milliseconds poll(2) may wait before the deadline; -1 (no limit) without one.
int wait_ms(bool limited, Clock::time_point deadline) {
  if (!limited) return -1;
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
  return static_cast<int>(std::clamp<long long>(left.count(), 0, 60 * 1000));
}

// Writes all of `text`; false when the worker is gone (EPIPE: SIGPIPE is ignored, see start).
bool write_all(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

// Gives the complete lines of `buffer` before the end line to `take`; true once the end line
// was seen (its status in `out`, the bytes after it left in `buffer`).
bool take_lines(std::string& buffer, JobOutcome& out,
                const std::function<void(const std::string&)>& take) {
  std::size_t start = 0;
  for (auto nl = buffer.find('\n'); nl != std::string::npos; nl = buffer.find('\n', start)) {
    std::string line = buffer.substr(start, nl - start);
    start = nl + 1;
    if (line.rfind(kJobEnd, 0) == 0) {
      const std::size_t rest = std::string(kJobEnd).size();
      out.end_status = line.size() > rest + 1 ? line.substr(rest + 1) : "";
      buffer.erase(0, start);
      return true;
    }
    take(line);
  }
  buffer.erase(0, start);
  return false;
}

}  // namespace

WorkerProcess::~WorkerProcess() {
  if (pid_ > 0) reap();
}

bool WorkerProcess::start(std::string& error) {
  // This process ignores SIGPIPE (a write to a dead worker is an EPIPE); its workers must not.
  ::signal(SIGPIPE, SIG_IGN);
  int in[2], out[2];
  // Close-on-exec: a worker started by another thread must not hold these pipes open.
  if (::pipe2(in, O_CLOEXEC) != 0) {
    error = std::string("cannot create a pipe: ") + std::strerror(errno);
    return false;
  }
  if (::pipe2(out, O_CLOEXEC) != 0) {
    error = std::string("cannot create a pipe: ") + std::strerror(errno);
    ::close(in[0]);
    ::close(in[1]);
    return false;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, in[0], STDIN_FILENO);
  posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t defaults;
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGPIPE);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF);
  std::vector<char*> argv;
  for (const std::string& a : args_) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const int rc = ::posix_spawn(&pid_, "/proc/self/exe", &actions, &attr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  ::close(in[0]);
  ::close(out[1]);
  to_worker_ = in[1];
  from_worker_ = out[0];
  if (rc != 0) {
    pid_ = -1;
    reap();
    error = std::string("cannot start a worker process: ") + std::strerror(rc);
    return false;
  }
  return true;
}

int WorkerProcess::reap() {
  if (to_worker_ >= 0) ::close(to_worker_);
  if (from_worker_ >= 0) ::close(from_worker_);
  to_worker_ = from_worker_ = -1;
  buffer_.clear();
  int status = 0;
  if (pid_ > 0) {
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
  }
  pid_ = -1;
  return status;
}

JobOutcome WorkerProcess::run(const std::string& job, double timeout_s,
                              const std::function<void(const std::string&)>& line) {
  JobOutcome outcome;
  if (pid_ < 0 && !start(outcome.spawn_error)) return outcome;
  const bool limited = timeout_s > 0 && timeout_s <= kMaxJobTimeoutS;
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(limited ? timeout_s : 0));
  bool alive = write_all(to_worker_, job + "\n");
  char chunk[1 << 16];
  while (alive && !(outcome.finished = take_lines(buffer_, outcome, line))) {
    if (limited && Clock::now() >= deadline) {
      outcome.timed_out = true;
      ::kill(pid_, SIGKILL);
      break;
    }
    pollfd p{from_worker_, POLLIN, 0};
    const int ready = ::poll(&p, 1, wait_ms(limited, deadline));
    if (ready < 0 && errno != EINTR) break;  // cannot wait on the worker: treat it as gone
    if (ready <= 0) continue;                // EINTR or the deadline
    const ssize_t n = ::read(from_worker_, chunk, sizeof chunk);
    if (n > 0) {
      buffer_.append(chunk, static_cast<std::size_t>(n));
    } else if (n == 0 || errno != EINTR) {
      alive = false;  // end of file: the worker died
    }
  }
  if (!outcome.finished) outcome.wait_status = reap();
  return outcome;
}

std::string describe_worker_end(const JobOutcome& w, double timeout_s) {
  if (!w.spawn_error.empty()) return w.spawn_error;
  if (w.timed_out) {
    return "timed out after " + format_double(timeout_s) + " s (--pair-timeout) and was killed";
  }
  if (WIFSIGNALED(w.wait_status)) {
    const int sig = WTERMSIG(w.wait_status);
    const char* abbrev = sigabbrev_np(sig);
    std::string why = "crashed: signal " + std::to_string(sig) +
                      (abbrev ? std::string(" (SIG") + abbrev + ")" : std::string());
    // The kernel's out-of-memory killer sends SIGKILL.
    if (sig == SIGKILL) why += "; killed from outside, e.g. for lack of memory";
    if (sig == SIGTERM || sig == SIGINT || sig == SIGHUP || sig == SIGQUIT) {
      why += "; stopped from outside (not its batch), e.g. by an out-of-memory daemon";
    }
    return why;
  }
  if (WIFEXITED(w.wait_status) && WEXITSTATUS(w.wait_status) != 0) {
    return "worker process exited with code " + std::to_string(WEXITSTATUS(w.wait_status)) +
           " without a result (its message is on stderr)";
  }
  return "worker process ended without a result";
}

}  // namespace qm3d::study
