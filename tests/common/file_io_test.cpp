#include "qm3d/common/file_io.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <csignal>
#include <fstream>
#include <thread>

#include "qm3d/common/error.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("qm3d_fileio_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(FileIo, MissingFileAndDirectoryAreNamed) {
  try {
    read_file_bytes("/nonexistent/x.ply");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/x.ply: no such file");
  }
  const fs::path d = temp_dir("dir");
  EXPECT_THROW(read_file_bytes(d), InputError);
  fs::remove_all(d);
}

TEST(FileIo, ReadsBytesExactly) {
  const fs::path d = temp_dir("read");
  std::ofstream(d / "a.bin", std::ios::binary) << std::string("a\0b", 3);
  EXPECT_EQ(read_file_bytes(d / "a.bin"), std::string("a\0b", 3));
  fs::remove_all(d);
}

TEST(FileIo, LowerExtension) {
  EXPECT_EQ(lower_extension("a/b/Mesh.PLY"), "ply");
  EXPECT_EQ(lower_extension("noext"), "");
}

TEST(FileIo, AtomicWriteLeavesNothingOnFailure) {
  const fs::path d = temp_dir("atomic");
  EXPECT_THROW(write_file_atomically(d / "out.txt",
                                     [](std::ostream& o) {
                                       o << "partial";
                                       throw std::runtime_error("boom");
                                     }),
               std::runtime_error);
  EXPECT_TRUE(fs::is_empty(d));
  write_file_atomically(d / "out.txt", [](std::ostream& o) { o << "done"; });
  EXPECT_EQ(read_file_bytes(d / "out.txt"), "done");
  EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator()), 1);
  EXPECT_THROW(write_file_atomically("/nonexistent/dir/out.txt", [](std::ostream&) {}),
               InputError);
  fs::remove_all(d);
}

// ---- non-regular inputs (issue 24 item 1) ----------------------------------------------------

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

fs::path make_fifo(const fs::path& dir) {
  const fs::path fifo = dir / "pipe";
  EXPECT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  return fifo;
}

// Writes `bytes` into the FIFO (opening blocks until the reader opened it); a reader that stops
// early is fine (EPIPE, SIGPIPE ignored).
std::thread fifo_writer(const fs::path& fifo, std::string bytes) {
  std::signal(SIGPIPE, SIG_IGN);
  return std::thread([fifo, bytes = std::move(bytes)] {
    const int fd = ::open(fifo.c_str(), O_WRONLY);
    for (std::size_t done = 0; fd >= 0 && done < bytes.size();) {
      const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
      if (n <= 0) break;
      done += static_cast<std::size_t>(n);
    }
    if (fd >= 0) ::close(fd);
  });
}

TEST(FileIo, DevicesAreRefusedNotRead) {
  EXPECT_EQ(message_of([] { read_file_bytes("/dev/zero", 1 << 20); }),
            "/dev/zero: not a regular file (character device)");
  EXPECT_EQ(message_of([] { read_file_bytes("/dev/urandom", 1 << 20); }),
            "/dev/urandom: not a regular file (character device)");
  EXPECT_EQ(file_kind("/dev/null"), "character device");
}

TEST(FileIo, RegularFileOverTheLimitIsRefused) {
  const fs::path d = temp_dir("limit");
  std::ofstream(d / "big.txt") << std::string(2000, 'x');
  EXPECT_NE(message_of([&] { read_file_bytes(d / "big.txt", 1000); }).find("file too large"),
            std::string::npos);
  EXPECT_EQ(read_file_bytes(d / "big.txt", 2000).size(), 2000u);
  fs::remove_all(d);
}

TEST(FileIo, ReadsAPipeInChunksToItsEnd) {
  const fs::path d = temp_dir("fifo_read");
  const fs::path fifo = make_fifo(d);
  std::string bytes(3 << 20, '\0');  // larger than a pipe's buffer
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<char>(i * 7);
  std::thread writer = fifo_writer(fifo, bytes);
  EXPECT_EQ(read_file_bytes(fifo), bytes);
  writer.join();
  fs::remove_all(d);
}

TEST(FileIo, PipeLongerThanTheLimitIsRefused) {
  const fs::path d = temp_dir("fifo_limit");
  const fs::path fifo = make_fifo(d);
  std::thread writer = fifo_writer(fifo, std::string(4 << 20, 'x'));
  EXPECT_NE(message_of([&] { read_file_bytes(fifo, 1 << 20); }).find("file too large"),
            std::string::npos);
  writer.join();
  fs::remove_all(d);
}

TEST(FileIo, FifoWithoutWriterGivesAnErrorInsteadOfBlocking) {
  const fs::path d = temp_dir("fifo_idle");
  const fs::path fifo = make_fifo(d);
  const std::string m =
      message_of([&] { read_file_bytes(fifo, 1 << 20, std::chrono::milliseconds(200)); });
  EXPECT_EQ(m.rfind(fifo.string() + ": no data from the pipe", 0), 0u) << m;
  fs::remove_all(d);
}

// ---- special outputs (issue 24 item 3) -------------------------------------------------------

TEST(FileIo, WritesIntoAFifoWithoutReplacingIt) {
  const fs::path d = temp_dir("fifo_write");
  const fs::path fifo = make_fifo(d);
  std::string received;
  std::thread reader([&] {
    const int fd = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
    pollfd p{fd, POLLIN, 0};
    char buf[256];
    while (::poll(&p, 1, 5000) > 0) {
      const ssize_t n = ::read(fd, buf, sizeof buf);
      if (n > 0) received.append(buf, static_cast<std::size_t>(n));
      if (n == 0 && !received.empty()) break;
    }
    ::close(fd);
  });
  ::usleep(100000);  // the reader opens the FIFO first (else the write waits for it)
  write_file_atomically(fifo, [](std::ostream& o) { o << "score\n"; });
  reader.join();
  EXPECT_EQ(received, "score\n");
  EXPECT_EQ(file_kind(fifo), "FIFO");
  EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator()), 1);
  fs::remove_all(d);
}

TEST(FileIo, WritesThroughASymlinkAndKeepsIt) {
  const fs::path d = temp_dir("symlink_write");
  std::ofstream(d / "target.txt") << "old";
  fs::create_symlink("target.txt", d / "link.txt");
  write_file_atomically(d / "link.txt", [](std::ostream& o) { o << "new"; });
  EXPECT_TRUE(fs::is_symlink(d / "link.txt"));
  EXPECT_EQ(read_file_bytes(d / "target.txt"), "new");
  fs::create_symlink("later.txt", d / "dangling.txt");
  write_file_atomically(d / "dangling.txt", [](std::ostream& o) { o << "made"; });
  EXPECT_TRUE(fs::is_symlink(d / "dangling.txt"));
  EXPECT_EQ(read_file_bytes(d / "later.txt"), "made");
  EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator()), 4);
  fs::remove_all(d);
}

// A device node of our own where we may make one (as root), so that a regression (a rename over
// the path) replaces only it; else the system's, which a user without root cannot replace.
fs::path device(const fs::path& dir, const std::string& name, unsigned minor) {
  const fs::path own = dir / name;
  if (::mknod(own.c_str(), S_IFCHR | 0600, makedev(1, minor)) == 0) return own;
  return fs::path("/dev") / name;
}

TEST(FileIo, DevicesAreWrittenIntoAndAFailedWriteNamesThePath) {
  const fs::path d = temp_dir("devices");
  const fs::path null = device(d, "null", 3), full = device(d, "full", 7);
  write_file_atomically(null, [](std::ostream& o) { o << "gone"; });
  EXPECT_EQ(file_kind(null), "character device");
  const std::string m =
      message_of([&] { write_file_atomically(full, [](std::ostream& o) { o << "x"; }); });
  EXPECT_EQ(m, full.string() + ": write failed (no space left on the device)");
  EXPECT_EQ(file_kind(full), "character device");
  fs::remove_all(d);
}

// ---- output checks (issue 24 item 3) ---------------------------------------------------------

TEST(FileIo, OutputsThatAreInputsOrEachOtherAreRefused) {
  const fs::path d = temp_dir("outputs");
  std::ofstream(d / "a.ply") << "a";
  fs::create_hard_link(d / "a.ply", d / "hard.ply");
  fs::create_symlink("a.ply", d / "soft.ply");
  const std::vector<NamedPath> in = {{"REF", d / "a.ply"}, {"DIST", d / "b.ply"}};
  EXPECT_EQ(message_of([&] {
              check_outputs(in, {{"-o", d / "a.ply"}});
            }),
            "-o " + (d / "a.ply").string() + ": is the input REF " + (d / "a.ply").string() +
                " (it would be overwritten)");
  EXPECT_NE(message_of([&] { check_outputs(in, {{"--map", d / "hard.ply"}}); }), "(no InputError)");
  EXPECT_NE(message_of([&] { check_outputs(in, {{"--map", d / "soft.ply"}}); }), "(no InputError)");
  EXPECT_NE(message_of([&] {
              check_outputs(in, {{"-o", d / "x"}, {"--map", d / "." / "x"}});
            }).find("is also the output -o"),
            std::string::npos);
  check_outputs(in, {{"-o", d / "x"}, {"--map", d / "y"}, {"--report", ""}});
  const fs::path null = device(d, "null", 3);
  check_outputs(in, {{"-o", null}, {"--map", null}});  // a device may take both
  EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator()),
            null.parent_path() == d ? 4 : 3);
  fs::remove_all(d);
}

TEST(FileIo, UnwritableOutputsAreFoundBeforehand) {
  const fs::path d = temp_dir("unwritable");
  EXPECT_EQ(message_of([&] {
              check_outputs({}, {{"--map", d / "none" / "m.ply"}});
            }),
            "--map " + (d / "none" / "m.ply").string() + ": the folder " + (d / "none").string() +
                " does not exist");
  EXPECT_EQ(message_of([&] {
              check_outputs({}, {{"-o", d}});
            }),
            "-o " + d.string() + ": is a directory");
  EXPECT_TRUE(fs::is_empty(d));
  fs::remove_all(d);
}

}  // namespace
}  // namespace qm3d
