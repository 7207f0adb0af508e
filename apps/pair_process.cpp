#include "pair_process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>

#include "qm3d/common/result_io.h"

extern char** environ;

namespace qm3d::app {
namespace {

using Clock = std::chrono::steady_clock;

// Milliseconds poll(2) may wait before the deadline; -1 (no limit) without one.
int wait_ms(bool limited, Clock::time_point deadline) {
  if (!limited) return -1;
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
  return left.count() <= 0 ? 0 : static_cast<int>(std::min<long long>(left.count(), 1000 * 60));
}

// Reads `fd` until end of file or the deadline; false when the deadline passed first.
bool read_until_eof(int fd, std::string& out, double timeout_s) {
  const bool limited = timeout_s > 0;
  const auto deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(
                         std::chrono::duration<double>(limited ? timeout_s : 0));
  char buffer[1 << 16];
  for (;;) {
    if (limited && Clock::now() >= deadline) return false;
    pollfd p{fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, wait_ms(limited, deadline));
    if (ready < 0 && errno == EINTR) continue;
    if (ready == 0) continue;  // the deadline is checked above
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n > 0) {
      out.append(buffer, static_cast<std::size_t>(n));
    } else if (n == 0 || errno != EINTR) {
      return true;
    }
  }
}

int wait_for(pid_t pid) {
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
}

}  // namespace

WorkerOutcome run_worker(const std::vector<std::string>& args, double timeout_s) {
  WorkerOutcome outcome;
  int fds[2];
  // Close-on-exec: a worker started by another thread must not hold this pipe open.
  if (::pipe2(fds, O_CLOEXEC) != 0) {
    outcome.spawn_error = std::string("cannot create a pipe: ") + std::strerror(errno);
    return outcome;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = ::posix_spawn(&pid, "/proc/self/exe", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[1]);
  if (rc != 0) {
    ::close(fds[0]);
    outcome.spawn_error = std::string("cannot start a worker process: ") + std::strerror(rc);
    return outcome;
  }
  if (!read_until_eof(fds[0], outcome.output, timeout_s)) {
    outcome.timed_out = true;
    ::kill(pid, SIGKILL);
  }
  ::close(fds[0]);
  outcome.wait_status = wait_for(pid);
  return outcome;
}

std::string describe_worker_end(const WorkerOutcome& w, double timeout_s) {
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
    return why;
  }
  if (WIFEXITED(w.wait_status) && WEXITSTATUS(w.wait_status) != 0) {
    return "worker process exited with code " + std::to_string(WEXITSTATUS(w.wait_status)) +
           " without a result (its message is on stderr)";
  }
  return "worker process ended without a result";
}

}  // namespace qm3d::app
