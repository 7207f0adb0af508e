#include "qm3d/common/file_io.h"

#include <gtest/gtest.h>

#include <fstream>

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

}  // namespace
}  // namespace qm3d
