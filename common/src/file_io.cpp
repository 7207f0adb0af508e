#include "qm3d/common/file_io.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <optional>
#include <random>
#include <streambuf>
#include <system_error>
#include <vector>

#include "qm3d/common/error.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;

std::string errno_text(int err) { return std::strerror(err); }

// Closes a descriptor on every path out of a scope.
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  int get() const { return fd_; }
  // Closes now; the errno of a failed close (NFS reports write errors there), else 0.
  int close() {
    const int rc = ::close(fd_);
    fd_ = -1;
    return rc == 0 ? 0 : errno;
  }

 private:
  int fd_;
};

std::string kind_of(mode_t mode) {
  if (S_ISREG(mode)) return "regular file";
  if (S_ISDIR(mode)) return "directory";
  if (S_ISFIFO(mode)) return "FIFO";
  if (S_ISCHR(mode)) return "character device";
  if (S_ISBLK(mode)) return "block device";
  if (S_ISSOCK(mode)) return "socket";
  return "special file";
}

void set_blocking(int fd) {
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
}

// ---- reading ---------------------------------------------------------------------------------

struct stat stat_for_reading(const fs::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int err = errno;
    if (err == ENOENT || err == ENOTDIR) throw InputError(path.string() + ": no such file");
    throw InputError(path.string() + ": cannot open for reading (" + errno_text(err) + ")");
  }
  if (S_ISDIR(st.st_mode)) throw InputError(path.string() + ": is a directory, not a file");
  // Devices (/dev/zero, /dev/urandom: endless) and sockets are refused before opening them:
  // opening a device can itself have effects (a tape rewinds, a terminal becomes ours).
  if (!S_ISREG(st.st_mode) && !S_ISFIFO(st.st_mode)) {
    throw InputError(path.string() + ": not a regular file (" + kind_of(st.st_mode) + ")");
  }
  return st;
}

InputError too_large(const fs::path& path, std::uintmax_t max_bytes) {
  return InputError(path.string() + ": file too large (over the limit of " +
                    std::to_string(max_bytes) + " bytes for this kind of file)");
}

// Waits until the pipe has data or its writer closed it; InputError after `wait` of silence.
void wait_for_pipe(int fd, const fs::path& path, std::chrono::milliseconds wait) {
  pollfd p{fd, POLLIN, 0};
  for (;;) {
    const int n = ::poll(&p, 1, static_cast<int>(wait.count()));
    if (n > 0) return;
    if (n == 0) {
      throw InputError(path.string() + ": no data from the pipe for " +
                       std::to_string(wait.count() / 1000.0).substr(0, 4) +
                       " s (does any program write to it?)");
    }
    if (errno != EINTR) {
      throw InputError(path.string() + ": read error (" + errno_text(errno) + ")");
    }
  }
}

// Reads `fd` to its end in chunks, never holding more than `max_bytes` (+1 to see the excess).
std::string read_all(int fd, const fs::path& path, std::uintmax_t max_bytes, bool pipe,
                     std::uintmax_t size_hint, std::chrono::milliseconds wait) {
  constexpr std::size_t kChunkBytes = std::size_t(1) << 16;
  const std::uintmax_t cap_limit = max_bytes + 1;
  std::string bytes;
  bytes.resize(static_cast<std::size_t>(
      std::min<std::uintmax_t>(std::max<std::uintmax_t>(size_hint + 1, kChunkBytes), cap_limit)));
  std::size_t used = 0;
  for (;;) {
    if (used == bytes.size()) {
      if (used >= cap_limit) throw too_large(path, max_bytes);
      bytes.resize(static_cast<std::size_t>(std::min<std::uintmax_t>(used * 2, cap_limit)));
    }
    if (pipe) wait_for_pipe(fd, path, wait);
    const ssize_t n = ::read(fd, bytes.data() + used, bytes.size() - used);
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      throw InputError(path.string() + ": read error (" + errno_text(errno) + ")");
    }
    if (n == 0) break;
    used += static_cast<std::size_t>(n);
  }
  if (used > max_bytes) throw too_large(path, max_bytes);
  bytes.resize(used);
  return bytes;
}

// ---- writing ---------------------------------------------------------------------------------

// An ostream buffer writing to a descriptor; remembers the first write error.
class FdWriteBuf : public std::streambuf {
 public:
  explicit FdWriteBuf(int fd) : fd_(fd), buffer_(kBufferBytes) { reset(); }
  int error() const { return error_; }

 protected:
  int_type overflow(int_type c) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  bool drain() {
    const char* p = pbase();
    while (error_ == 0 && p < pptr()) {
      const ssize_t n = ::write(fd_, p, static_cast<std::size_t>(pptr() - p));
      if (n >= 0) {
        p += n;
      } else if (errno == EAGAIN) {  // an inherited non-blocking descriptor
        pollfd w{fd_, POLLOUT, 0};
        ::poll(&w, 1, -1);
      } else if (errno != EINTR) {
        error_ = errno;
      }
    }
    reset();
    return error_ == 0;
  }
  void reset() { setp(buffer_.data(), buffer_.data() + buffer_.size()); }

  static constexpr std::size_t kBufferBytes = std::size_t(1) << 16;
  int fd_;
  int error_ = 0;
  std::vector<char> buffer_;
};

// Runs `write` into `fd`; the errno of the first failed write, else 0. Exceptions of `write`
// pass through.
int write_into(int fd, const std::function<void(std::ostream&)>& write) {
  FdWriteBuf buf(fd);
  std::ostream out(&buf);
  write(out);
  out.flush();
  if (buf.error() != 0) return buf.error();
  return out ? 0 : EIO;
}

InputError write_failed(const fs::path& path, int err) {
  const std::string why = err == EPIPE    ? "the reader closed the pipe"
                          : err == ENOSPC ? "no space left on the device"
                                          : errno_text(err);
  return InputError(path.string() + ": write failed (" + why + ")");
}

// The descriptor a standard-stream path names: /dev/stdout, /dev/stderr, /dev/fd/N,
// /proc/self/fd/N, /proc/<our pid>/fd/N. Renaming over these would replace a link of /dev or
// /proc; reopening them fails for sockets; so they are written through the descriptor itself.
std::optional<int> standard_stream_fd(const fs::path& path) {
  const std::string p = path.lexically_normal().string();
  if (p == "/dev/stdout") return 1;
  if (p == "/dev/stderr") return 2;
  for (const std::string& prefix :
       {std::string("/dev/fd/"), std::string("/proc/self/fd/"),
        std::string("/proc/thread-self/fd/"), "/proc/" + std::to_string(::getpid()) + "/fd/"}) {
    if (p.rfind(prefix, 0) != 0) continue;
    const std::string n = p.substr(prefix.size());
    if (n.empty() || n.size() > 9 || !std::all_of(n.begin(), n.end(), ::isdigit)) return {};
    return std::stoi(n);
  }
  return {};
}

void write_to_stream_fd(const fs::path& path, int fd,
                        const std::function<void(std::ostream&)>& write) {
  if (::fcntl(fd, F_GETFD) < 0) throw InputError(path.string() + ": not an open descriptor");
  // What the program already wrote to its own streams comes first.
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  if (const int err = write_into(fd, write)) throw write_failed(path, err);
}

// Opens a FIFO for writing without blocking forever when no program reads it.
int open_fifo_for_writing(const fs::path& path) {
  constexpr auto kRetry = std::chrono::milliseconds(50);
  for (auto waited = std::chrono::milliseconds(0); waited < kPipeIdleWait; waited += kRetry) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd >= 0) {
      set_blocking(fd);
      return fd;
    }
    if (errno != ENXIO) {  // ENXIO: no reader yet
      throw InputError(path.string() + ": cannot write (" + errno_text(errno) + ")");
    }
    ::poll(nullptr, 0, static_cast<int>(kRetry.count()));
  }
  throw InputError(path.string() + ": no program reads the FIFO (waited " +
                   std::to_string(kPipeIdleWait.count() / 1000) + " s)");
}

// A FIFO or a device: written into, never replaced.
void write_into_special(const fs::path& path, mode_t mode,
                        const std::function<void(std::ostream&)>& write) {
  if (S_ISSOCK(mode)) throw InputError(path.string() + ": cannot write (a socket)");
  int raw = -1;
  if (S_ISFIFO(mode)) {
    raw = open_fifo_for_writing(path);
  } else {
    raw = ::open(path.c_str(), O_WRONLY | O_CLOEXEC | O_NOCTTY);
    if (raw < 0) throw InputError(path.string() + ": cannot write (" + errno_text(errno) + ")");
  }
  Fd fd(raw);
  int err = write_into(fd.get(), write);
  const int close_err = fd.close();
  if (err == 0) err = close_err;
  if (err != 0) throw write_failed(path, err);
}

// Follows a chain of symlinks (dangling ones included) to the path that is not a symlink.
fs::path follow_symlinks(const fs::path& path) {
  constexpr int kMaxLinks = 40;  // Linux's own limit (ELOOP)
  fs::path p = path;
  for (int i = 0; i < kMaxLinks; ++i) {
    std::error_code ec;
    if (!fs::is_symlink(fs::symlink_status(p, ec))) return p;
    const fs::path target = fs::read_symlink(p, ec);
    if (ec) throw InputError(path.string() + ": cannot read the symlink (" + ec.message() + ")");
    p = target.is_absolute() ? target : p.parent_path() / target;
  }
  throw InputError(path.string() + ": too many levels of symlinks");
}

// A new file beside `target` that no other process can have made or redirected.
struct TempFile {
  fs::path path;
  int fd = -1;    ///< -1 when none could be created
  int error = 0;  ///< errno then
};

TempFile try_create_temp_beside(const fs::path& target) {
  thread_local std::mt19937_64 rng{std::random_device{}() ^
                             (static_cast<std::uint64_t>(::getpid()) << 32)};
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  constexpr int kAttempts = 16;
  int err = EEXIST;
  for (int i = 0; i < kAttempts && err == EEXIST; ++i) {
    char suffix[40];
    std::snprintf(suffix, sizeof suffix, ".qm3d-tmp-%d-%016llx", static_cast<int>(::getpid()),
                  static_cast<unsigned long long>(rng()));
    const fs::path tmp = dir / (target.filename().string() + suffix);
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd >= 0) return {tmp, fd, 0};
    err = errno;
  }
  return {{}, -1, err};
}

void write_regular_atomically(const fs::path& shown, const fs::path& target,
                              const std::function<void(std::ostream&)>& write) {
  const TempFile tmp = try_create_temp_beside(target);
  if (tmp.fd < 0) {
    throw InputError(shown.string() + ": cannot write (" + errno_text(tmp.error) + ")");
  }
  Fd fd(tmp.fd);
  const auto discard = [&] { ::unlink(tmp.path.c_str()); };
  struct stat old {};
  if (::stat(target.c_str(), &old) == 0) ::fchmod(fd.get(), old.st_mode & 07777);  // keep mode
  int err = 0;
  try {
    err = write_into(fd.get(), write);
  } catch (...) {
    fd.close();
    discard();
    throw;
  }
  const int close_err = fd.close();
  if (err == 0) err = close_err;
  if (err != 0) {
    discard();
    throw write_failed(shown, err);
  }
  if (::rename(tmp.path.c_str(), target.c_str()) != 0) {
    err = errno;
    discard();
    throw InputError(shown.string() + ": cannot write (" + errno_text(err) + ")");
  }
}

// ---- output checks ---------------------------------------------------------------------------

InputError output_error(const NamedPath& o, const std::string& why) {
  return InputError(o.option + " " + o.path.string() + ": " + why);
}

void check_writable(const NamedPath& o) {
  if (standard_stream_fd(o.path)) {
    if (::fcntl(*standard_stream_fd(o.path), F_GETFD) < 0) {
      throw output_error(o, "not an open descriptor");
    }
    return;
  }
  const fs::path target = follow_symlinks(o.path);
  struct stat st {};
  if (::stat(target.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) throw output_error(o, "is a directory");
    if (!S_ISREG(st.st_mode)) return;  // a FIFO or a device: opened when written
  }
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  struct stat d {};
  if (::stat(dir.c_str(), &d) != 0 || !S_ISDIR(d.st_mode)) {
    throw output_error(o, "the folder " + dir.string() + " does not exist");
  }
  // Creating the temporary file is the one test that also holds for root and read-only mounts.
  const TempFile probe = try_create_temp_beside(target);
  if (probe.fd < 0) {
    throw output_error(
        o, "cannot create a file in " + dir.string() + " (" + errno_text(probe.error) + ")");
  }
  ::close(probe.fd);
  ::unlink(probe.path.c_str());
}

// The identity of an existing regular file or the canonical form of a new path; nothing for
// FIFOs, devices and standard streams (writing twice into them replaces nothing).
struct FileIdentity {
  bool exists = false;
  dev_t dev = 0;
  ino_t ino = 0;
  fs::path canonical;
};

std::optional<FileIdentity> identity(const fs::path& path) {
  if (path.empty() || standard_stream_fd(path)) return {};
  struct stat st {};
  FileIdentity id;
  if (::stat(path.c_str(), &st) == 0) {
    if (!S_ISREG(st.st_mode)) return {};
    id.exists = true;
    id.dev = st.st_dev;
    id.ino = st.st_ino;
    return id;
  }
  std::error_code ec;
  id.canonical = fs::weakly_canonical(follow_symlinks(path), ec);
  if (ec) id.canonical = fs::absolute(path).lexically_normal();
  return id;
}

bool same(const FileIdentity& a, const FileIdentity& b) {
  if (a.exists != b.exists) return false;
  return a.exists ? a.dev == b.dev && a.ino == b.ino : a.canonical == b.canonical;
}

}  // namespace

std::string read_file_bytes(const fs::path& path, std::uintmax_t max_bytes,
                            std::chrono::milliseconds pipe_idle_wait) {
  const struct stat named = stat_for_reading(path);
  // O_NONBLOCK: opening a FIFO that has no writer must not block (the wait is bounded below).
  Fd fd(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY));
  if (fd.get() < 0) {
    throw InputError(path.string() + ": cannot open for reading (" + errno_text(errno) + ")");
  }
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0 || (st.st_mode & S_IFMT) != (named.st_mode & S_IFMT)) {
    throw InputError(path.string() + ": changed while being opened");
  }
  const bool pipe = S_ISFIFO(st.st_mode);
  if (!pipe) {
    if (static_cast<std::uintmax_t>(st.st_size) > max_bytes) throw too_large(path, max_bytes);
    set_blocking(fd.get());
  }
  return read_all(fd.get(), path, max_bytes, pipe, pipe ? 0 : std::uintmax_t(st.st_size),
                  pipe_idle_wait);
}

std::string file_kind(const fs::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) return kind_of(st.st_mode);
  std::error_code ec;
  return fs::is_symlink(fs::symlink_status(path, ec)) ? "symlink" : "missing";
}

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

void write_file_atomically(const fs::path& path, const std::function<void(std::ostream&)>& write) {
  if (const auto fd = standard_stream_fd(path)) return write_to_stream_fd(path, *fd, write);
  const fs::path target = follow_symlinks(path);
  struct stat st {};
  if (::stat(target.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    if (S_ISDIR(st.st_mode)) throw InputError(path.string() + ": is a directory");
    return write_into_special(path, st.st_mode, write);
  }
  write_regular_atomically(path, target, write);
}

bool same_file(const fs::path& a, const fs::path& b) {
  const auto id = identity(a), other = identity(b);
  return id && other && same(*id, *other);
}

void check_outputs(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs) {
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const NamedPath& o = outputs[i];
    if (o.path.empty()) continue;
    for (const NamedPath& in : inputs) {
      if (same_file(in.path, o.path)) {
        throw output_error(
            o, "is the input " + in.option + " " + in.path.string() + " (it would be overwritten)");
      }
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (same_file(outputs[j].path, o.path)) {
        throw output_error(o, "is also the output " + outputs[j].option + " (one would be lost)");
      }
    }
    check_writable(o);
  }
}

fs::path installed_share_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec || exe.empty()) return {};
  const fs::path share = exe.parent_path().parent_path() / "share" / "qm3d";
  return fs::is_directory(share, ec) ? share : fs::path();
}

}  // namespace qm3d
