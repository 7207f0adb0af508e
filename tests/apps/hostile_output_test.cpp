// Hostile paths for qm3d's inputs and outputs (issue 24 items 1 and 3): devices and pipes as
// inputs, outputs that are inputs or each other, outputs that are FIFOs, symlinks, devices or
// standard streams, outputs that cannot be written, a reader that closes the pipe. Every case
// either works as documented or exits 2 with one line naming the option and the path; no input
// or special file is ever replaced, no temporary file is left behind.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>

#include "cli_runner.h"
#include "test_paths.h"

extern char** environ;

namespace qm3d {
namespace {

namespace fs = std::filesystem;
using test::CliRun;
using test::slurp;

class HostileIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_hostile_io_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "io");
    const fs::path data = test::source_dir() / "data";
    fs::copy_file(data / "clouds" / "sphere_2k_ref.ply", dir_ / "a.ply");
    fs::copy_file(data / "clouds" / "sphere_2k_cnoise10.ply", dir_ / "b.ply");
    fs::copy_file(data / "meshes" / "blob3_ref.off", dir_ / "m.off");
    fs::copy_file(data / "meshes" / "blob3_colnoise.off", dir_ / "m2.off");
    original_b_ = slurp(dir_ / "b.ply");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // `qm3d ARGS` run in dir_ (paths relative to it), with $QM3D_DATA_DIR set.
  CliRun run(const std::string& args) {
    return test::run_qm3d("-q " + args, dir_, dir_ / "io",
                          "QM3D_DATA_DIR='" + test::tables_dir().string() + "'");
  }

  // Shell text run in dir_ with $QM3D_DATA_DIR set and $QM3D the binary (for the cases that run
  // qm3d beside another program).
  void shell(const std::string& text) {
    const std::string cmd = "cd '" + dir_.string() + "' && export QM3D_DATA_DIR='" +
                            test::tables_dir().string() + "' QM3D='" + QM3D_BINARY + "' && { " +
                            text + "; }";
    ASSERT_NE(std::system(cmd.c_str()), -1);
  }

  fs::path file(const std::string& name, const std::string& content) {
    std::ofstream(dir_ / name, std::ios::binary) << content;
    return dir_ / name;
  }

  // Exit 2, one line on stderr containing each of `parts`, nothing on stdout.
  static void expect_refused(const CliRun& o, const std::vector<std::string>& parts) {
    EXPECT_EQ(o.code, 2) << o.err;
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
    EXPECT_EQ(o.err.rfind("qm3d: error: ", 0), 0u) << o.err;
    for (const std::string& p : parts) EXPECT_NE(o.err.find(p), std::string::npos) << o.err;
    EXPECT_EQ(o.out, "");
  }

  // Only the files SetUp made (and `extra`), so no temporary file was left.
  void expect_no_leftovers(std::size_t extra = 0) const {
    std::size_t n = 0;
    for (const auto& e : fs::directory_iterator(dir_)) {
      n += e.path().filename() != "io";
      EXPECT_EQ(e.path().filename().string().find("tmp"), std::string::npos) << e.path();
    }
    EXPECT_EQ(n, 4 + extra);
  }

  fs::path dir_;
  std::string original_b_;
};

// Six stimuli: enough for the logistic fit, so that eval reaches its bootstrap.
const std::string kScores = "distorted,score\na,1\nb,2\nc,3\nd,4\ne,5\nf,6\n";
const std::string kMos = "stimulus,mos\na,1\nb,2.5\nc,2\nd,4\ne,4.5\nf,5\n";

// ---- outputs that are inputs or each other ---------------------------------------------------

TEST_F(HostileIo, AnOutputThatIsAnInputIsRefused) {
  expect_refused(run("pcqm a.ply b.ply -o b.ply"), {"-o b.ply: is the input DIST b.ply"});
  expect_refused(run("pcqm a.ply b.ply --map ./b.ply"), {"--map ./b.ply: is the input DIST"});
  expect_refused(run("pcqm a.ply b.ply --report b.ply"), {"--report b.ply: is the input DIST"});
  expect_refused(run("report a.ply b.ply -o b.ply"), {"-o b.ply: is the input DIST"});
  expect_refused(run("sample m.off --points 100 -o m.off"), {"-o m.off: is the input MESH"});
  EXPECT_EQ(slurp(dir_ / "b.ply"), original_b_);
  expect_no_leftovers();
}

TEST_F(HostileIo, HardLinksAndSymlinksOfAnInputCount) {
  fs::create_hard_link(dir_ / "b.ply", dir_ / "hard.ply");
  fs::create_symlink("b.ply", dir_ / "soft.ply");
  expect_refused(run("pcqm a.ply b.ply -o hard.ply"), {"-o hard.ply: is the input DIST b.ply"});
  expect_refused(run("pcqm a.ply b.ply --map soft.ply"), {"--map soft.ply: is the input DIST"});
  EXPECT_EQ(slurp(dir_ / "b.ply"), original_b_);
  expect_no_leftovers(2);
}

TEST_F(HostileIo, TwoOutputsOnOnePathAreRefused) {
  expect_refused(run("pcqm a.ply b.ply -o x.ply --map x.ply"),
                 {"--map x.ply: is also the output -o"});
  expect_no_leftovers();
}

// ---- special outputs ---------------------------------------------------------------------------

TEST_F(HostileIo, OutputIntoAFifoKeepsTheFifo) {
  ASSERT_EQ(::mkfifo((dir_ / "fifo").c_str(), 0600), 0);
  // The reader runs beside qm3d; `timeout` ends either if the other never comes.
  shell(
      "(/usr/bin/timeout 60 \"$QM3D\" -q pcqm a.ply b.ply -o fifo 2> io/err &) ; "
      "/usr/bin/timeout 60 cat fifo > io/got; wait");
  EXPECT_EQ(slurp(dir_ / "io" / "err"), "");
  EXPECT_EQ(slurp(dir_ / "io" / "got").rfind("PCQM = ", 0), 0u) << slurp(dir_ / "io" / "got");
  EXPECT_TRUE(fs::is_fifo(dir_ / "fifo"));
  expect_no_leftovers(1);
}

TEST_F(HostileIo, OutputThroughASymlinkKeepsTheLink) {
  fs::create_symlink("target.txt", dir_ / "link.txt");
  const CliRun o = run("pcqm a.ply b.ply -o link.txt");
  EXPECT_EQ(o.code, 0) << o.err;
  EXPECT_TRUE(fs::is_symlink(dir_ / "link.txt"));
  EXPECT_EQ(slurp(dir_ / "target.txt").rfind("PCQM = ", 0), 0u);
  expect_no_leftovers(2);
}

// The standard streams are named /dev/fd/N and /proc/self/fd/N here, not /dev/stdout: the same
// code path, but a regression (renaming over the path) cannot then replace /dev/stdout of the
// machine running the tests as root.
TEST_F(HostileIo, OutputToAStandardStreamGoesToThatStream) {
  for (const std::string stream : {"/dev/fd/1", "/proc/self/fd/1"}) {
    const CliRun o = run("pcqm a.ply b.ply --csv -o " + stream);
    EXPECT_EQ(o.code, 0) << o.err;
    EXPECT_EQ(o.out.rfind("reference,distorted,metric,", 0), 0u) << o.out;
  }
  const CliRun o = run("pcqm a.ply b.ply -o /dev/fd/2");
  EXPECT_EQ(o.code, 0) << o.err;
  EXPECT_EQ(o.err.rfind("PCQM = ", 0), 0u) << o.err;
  expect_no_leftovers();
}

TEST_F(HostileIo, AFullDeviceIsAWriteErrorNamingIt) {
  // A device of our own where we may make one (as root), so that a regression replaces only
  // it; else /dev/full, which a user without root cannot replace.
  const bool own = ::mknod((dir_ / "full").c_str(), S_IFCHR | 0600, makedev(1, 7)) == 0;
  const std::string device = own ? "full" : "/dev/full";
  expect_refused(run("pcqm a.ply b.ply -o " + device),
                 {device + ": write failed (no space left on the device)"});
  EXPECT_TRUE(fs::is_character_file(own ? dir_ / "full" : fs::path("/dev/full")));
  expect_no_leftovers(own ? 1 : 0);
}

// Runs qm3d with its stdout on a pipe whose reader is already gone; the exit code, -1 on a
// signal.
int run_into_closed_pipe(const std::vector<std::string>& args, const fs::path& err_file) {
  int fds[2];
  if (::pipe(fds) != 0) return -2;
  ::close(fds[0]);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
  posix_spawn_file_actions_addopen(&actions, 2, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0600);
  std::vector<std::string> all = {QM3D_BINARY};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  const std::string env = "QM3D_DATA_DIR=" + test::tables_dir().string();
  std::vector<char*> envp = {const_cast<char*>(env.c_str()), nullptr};
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, QM3D_BINARY, &actions, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[1]);
  if (rc != 0) return -2;
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST_F(HostileIo, AClosedPipeIsAnErrorNotASilentDeath) {
  const fs::path a = dir_ / "a.ply", b = dir_ / "b.ply", err = dir_ / "io" / "err";
  EXPECT_EQ(run_into_closed_pipe({"-q", "pcqm", a.string(), b.string()}, err), 2);
  EXPECT_EQ(slurp(err), "qm3d: error: stdout: write failed\n");
  EXPECT_EQ(run_into_closed_pipe({"-q", "pcqm", a.string(), b.string(), "-o", "/dev/fd/1"}, err),
            2);
  EXPECT_EQ(slurp(err), "qm3d: error: /dev/fd/1: write failed (the reader closed the pipe)\n");
}

// ---- outputs checked before scoring ----------------------------------------------------------

TEST_F(HostileIo, UnwritableOutputsAreRefusedBeforeScoring) {
  expect_refused(run("pcqm a.ply b.ply -o none/x.txt"),
                 {"-o none/x.txt: the folder none does not exist"});
  expect_refused(run("pcqm a.ply b.ply --map io"), {"--map io: is a directory"});
  expect_refused(run("compare m.off m2.off --report none/r.html"),
                 {"--report none/r.html: the folder none does not exist"});
  expect_refused(run("sample m.off --points 10 -o io"), {"-o io: is a directory"});
  file("s.csv", kScores);
  file("mos.csv", kMos);
  expect_refused(run("eval s.csv mos.csv --plot none/p.svg"),
                 {"--plot none/p.svg: the folder none does not exist"});
  expect_refused(run("eval s.csv mos.csv -o s.csv"), {"-o s.csv: is the input SCORES"});
  expect_no_leftovers(2);
}

// ---- non-regular inputs ------------------------------------------------------------------------

TEST_F(HostileIo, DevicesAsInputsAreRefused) {
  expect_refused(run("pcqm /dev/zero b.ply"), {"/dev/zero: not a regular file (character device)"});
  file("t.obj",
       "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nmtllib t.mtl\nusemtl m\n"
       "f 1/1 2/2 3/3\n");
  file("t.mtl", "newmtl m\nmap_Kd /dev/zero\n");
  expect_refused(run("cmdm t.obj t.obj"), {"/dev/zero: not a regular file (character device)"});
  file("u.obj",
       "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nmtllib /dev/urandom\n"
       "usemtl m\nf 1/1 2/2 3/3\n");
  expect_refused(run("cmdm u.obj u.obj"), {"/dev/urandom: not a regular file (character device)"});
  expect_refused(run("cmdm m.off m2.off --model /dev/zero"), {"/dev/zero: not a regular file"});
  file("mos.csv", kMos);
  expect_refused(run("eval /dev/urandom mos.csv"), {"/dev/urandom: not a regular file"});
}

TEST_F(HostileIo, APipeIsReadAsAFile) {
  const CliRun files = run("pcqm a.ply b.ply");
  ASSERT_EQ(files.code, 0) << files.err;
  ASSERT_EQ(::mkfifo((dir_ / "fifo").c_str(), 0600), 0);
  shell(
      "/usr/bin/timeout 60 \"$QM3D\" -q pcqm a.ply fifo > io/out 2> io/err & "
      "/usr/bin/timeout 60 cat b.ply > fifo; wait $!; echo $? > io/rc");
  EXPECT_EQ(slurp(dir_ / "io" / "rc"), "0\n") << slurp(dir_ / "io" / "err");
  EXPECT_EQ(slurp(dir_ / "io" / "out"), files.out);
  EXPECT_EQ(slurp(dir_ / "io" / "err"), "");
}

TEST_F(HostileIo, WarningsOfAPipeNameThePipeNotItsInMemoryCopy) {
  // One colour value just above 1 makes the reader warn (the scale is decided on one value).
  file("t.off", "COFF\n3 1 0\n0 0 0 1.0000001 0 0 1\n1 0 0 0 1 0 1\n0 1 0 0 0 1 1\n3 0 1 2\n");
  ASSERT_EQ(::mkfifo((dir_ / "tfifo").c_str(), 0600), 0);
  shell(
      "/usr/bin/timeout 60 \"$QM3D\" msdm2 t.off tfifo > io/out 2> io/err & "
      "/usr/bin/timeout 60 cat t.off > tfifo; wait $!; echo $? > io/rc");
  EXPECT_EQ(slurp(dir_ / "io" / "rc"), "0\n") << slurp(dir_ / "io" / "err");
  const std::string err = slurp(dir_ / "io" / "err");
  EXPECT_NE(err.find("tfifo: 1 of 9 colour values above 1"), std::string::npos) << err;
  EXPECT_EQ(err.find("/proc/self/fd"), std::string::npos) << err;
}

// ---- eval --bootstrap ------------------------------------------------------------------------

TEST_F(HostileIo, BootstrapCountIsBounded) {
  file("s.csv", kScores);
  file("mos.csv", kMos);
  const CliRun negative = run("eval s.csv mos.csv --bootstrap -1");
  EXPECT_EQ(negative.code, 1) << negative.err;
  EXPECT_NE(negative.err.find("--bootstrap"), std::string::npos) << negative.err;
  const CliRun huge = run("eval s.csv mos.csv --bootstrap 1099511627776");
  EXPECT_EQ(huge.code, 1) << huge.err;
  EXPECT_NE(huge.err.find("--bootstrap"), std::string::npos) << huge.err;
}

}  // namespace
}  // namespace qm3d
