// `qm3d batch` and `qm3d merge` against faults and hostile files (issue 24): a pair that crashes
// its process, a resume with other settings, onto the list or an unrelated file, a second batch
// on the same results, error rows left behind, lists with a BOM or reordered columns, shards
// with a non-number score or missing.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "cli_runner.h"
#include "qm3d/common/result_io.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;
using test::CliRun;
using test::slurp;

class BatchHostile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_batch_hostile_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "io");
    list_ = dir_ / "list.csv";
    results_ = dir_ / "results.csv";
  }
  void TearDown() override { fs::remove_all(dir_); }

  CliRun qm3d(const std::string& args, const std::string& env = "") {
    return test::run_qm3d(args, dir_, dir_ / "io",
                          "QM3D_DATA_DIR='" + test::tables_dir().string() + "' " + env);
  }
  std::string batch(const std::string& extra = "") const {
    return "batch '" + list_.string() + "' -o '" + results_.string() + "' --quiet " + extra;
  }
  static std::string mesh(const std::string& name) {
    return (test::reference_dir() / "cmdm" / name).string();
  }
  // A list of blob4_ref against each of `distorted` (files of the CMDM reference data), CMDM.
  void write_list(const std::vector<std::string>& distorted) const {
    std::ofstream l(list_);
    l << "reference,distorted,metric\n";
    for (const auto& d : distorted) l << mesh("blob4_ref.off") << "," << mesh(d) << ",cmdm\n";
  }

  fs::path dir_, list_, results_;
};

// distorted file name -> (status, error) of each row; counts rows per key in `count`.
struct Rows {
  std::map<std::string, std::pair<std::string, std::string>> by_name;
  std::map<std::string, int> count;
  std::vector<std::string> header;
};
Rows read_rows(const fs::path& results) {
  Rows rows;
  std::istringstream in(slurp(results));
  std::string line;
  std::getline(in, line);
  rows.header = csv_split(line);
  while (std::getline(in, line)) {
    const auto f = csv_split(line);
    if (f.size() < 6) continue;
    const std::string name = fs::path(f[1]).filename().string();
    rows.by_name[name] = {f[4], f[5]};
    ++rows.count[name + "," + f[2]];
  }
  return rows;
}

// ---- a pair never takes the batch down ---------------------------------------------------------

TEST_F(BatchHostile, APairThatCrashesIsItsErrorRowAndTheBatchGoesOn) {
  write_list({"blob4_colnoise.off", "blob4_geonoise.off", "blob4_bothnoise.off"});
  const std::string crash = "QM3D_TEST_FAULT=segv:blob4_geonoise.off";
  const CliRun r = qm3d(batch("--jobs 2"), crash);
  EXPECT_EQ(r.code, 2) << r.err;  // finished, with an error row
  Rows rows = read_rows(results_);
  ASSERT_EQ(rows.by_name.size(), 3u) << slurp(results_);
  EXPECT_EQ(rows.by_name["blob4_geonoise.off"].first, "error");
  EXPECT_EQ(rows.by_name["blob4_geonoise.off"].second, "crashed: signal 11 (SIGSEGV)");
  EXPECT_EQ(rows.by_name["blob4_colnoise.off"].first, "ok");  // the pair beside it
  EXPECT_EQ(rows.by_name["blob4_bothnoise.off"].first, "ok");
  // --resume does not die on it again (nor retry it), and still says an error row remains.
  EXPECT_EQ(qm3d(batch("--resume"), crash).code, 2);
  // --retry-failed scores it again, replacing its error row.
  const CliRun retried = qm3d(batch("--resume --retry-failed"));
  EXPECT_EQ(retried.code, 0) << retried.err;
  rows = read_rows(results_);
  for (const auto& [key, n] : rows.count) EXPECT_EQ(n, 1) << key;
  for (const auto& [name, row] : rows.by_name) EXPECT_EQ(row.first, "ok") << name;
  EXPECT_EQ(rows.by_name.size(), 3u);
}

TEST_F(BatchHostile, AnAbortAndAHangAreErrorRowsToo) {
  // One job at a time: the pair after the abort is scored by a new worker.
  write_list({"blob4_colnoise.off", "blob4_geonoise.off", "blob4_bothnoise.off"});
  CliRun r = qm3d(batch(), "QM3D_TEST_FAULT=abort:blob4_geonoise.off");
  EXPECT_EQ(r.code, 2) << r.err;
  Rows rows = read_rows(results_);
  EXPECT_EQ(rows.by_name["blob4_geonoise.off"].second, "crashed: signal 6 (SIGABRT)");
  EXPECT_EQ(rows.by_name["blob4_colnoise.off"].first, "ok");
  EXPECT_EQ(rows.by_name["blob4_bothnoise.off"].first, "ok");
  // Alone in its list: under --pair-timeout, a slow machine must not time out another pair.
  write_list({"blob4_geonoise.off"});
  r = qm3d(batch("--overwrite --pair-timeout 2"), "QM3D_TEST_FAULT=hang:blob4_geonoise.off");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(read_rows(results_).by_name["blob4_geonoise.off"].second,
            "timed out after 2 s (--pair-timeout) and was killed");
}

// Isolation changes where a pair is scored, not its row: the same rows (every column but
// seconds) with and without worker processes, for a compare pair (several rows per pair).
TEST_F(BatchHostile, WorkersWriteTheRowsThisProcessWould) {
  std::ofstream(list_) << mesh("blob4_ref.off") << "," << mesh("blob4_colnoise.off") << ",compare\n"
                       << mesh("blob4_ref.off") << ",missing.off,cmdm\n";
  const auto rows_without_seconds = [&](const std::string& extra) {
    fs::remove(results_);
    const CliRun r = qm3d(batch("--jobs 2 --points 500 " + extra));
    EXPECT_EQ(r.code, 2) << r.err;
    std::multiset<std::string> rows;
    std::istringstream in(slurp(results_));
    std::string line;
    while (std::getline(in, line)) {
      auto f = csv_split(line);
      if (f.size() > 6) f[6].clear();  // seconds
      std::string joined;
      for (const auto& field : f) joined += field + "|";
      rows.insert(joined);
    }
    return rows;
  };
  const auto isolated = rows_without_seconds("");
  EXPECT_EQ(isolated.size(), 7u);  // header, 5 metrics of compare, the missing file
  EXPECT_EQ(isolated, rows_without_seconds("--no-isolation"));
}

// A mesh with one face repeated 60,000 times crashed CMDM (a recursion too deep in the
// projection's k-d tree). Whether it scores now or fails, the batch finishes with every row.
TEST_F(BatchHostile, AGenuinelyCrashingInputLeavesEveryRow) {
  const fs::path repeated = dir_ / "repeated_face.off";
  {
    std::ofstream m(repeated);
    m << "COFF\n4 60000 0\n0 0 0 200 10 10 255\n1 0 0 10 200 10 255\n0 1 0 10 10 200 255\n"
         "0 0 1 100 100 100 255\n";
    for (int i = 0; i < 60000; ++i) m << "3 0 1 2\n";
  }
  std::ofstream(list_) << repeated.string() << "," << repeated.string() << ",cmdm\n"
                       << mesh("blob4_ref.off") << "," << mesh("blob4_colnoise.off") << ",cmdm\n";
  const CliRun r = qm3d(batch("--jobs 2"));
  EXPECT_TRUE(r.code == 0 || r.code == 2) << "qm3d died: " << r.code << " " << r.err;
  const Rows rows = read_rows(results_);
  EXPECT_EQ(rows.by_name.size(), 2u) << slurp(results_);
  EXPECT_EQ(rows.by_name.at("blob4_colnoise.off").first, "ok");
}

// A batch stopped from outside (Ctrl-C reaches its process group, scancel every process of the
// job) records no error row for the pairs its workers were scoring: --resume scores them.
TEST_F(BatchHostile, AWorkerStoppedAloneIsItsPairsErrorRowAndTheBatchGoesOn) {
  // SIGTERM to one worker (earlyoom, systemd-oomd, a stray kill), not to the batch.
  write_list({"blob4_colnoise.off", "blob4_geonoise.off", "blob4_bothnoise.off"});
  const CliRun r = qm3d(batch(), "QM3D_TEST_FAULT=term:blob4_geonoise.off");
  EXPECT_EQ(r.code, 2) << r.err;
  const Rows rows = read_rows(results_);
  ASSERT_EQ(rows.by_name.size(), 3u) << slurp(results_);
  EXPECT_EQ(rows.by_name.at("blob4_colnoise.off").first, "ok");
  EXPECT_EQ(rows.by_name.at("blob4_bothnoise.off").first, "ok");
  EXPECT_NE(rows.by_name.at("blob4_geonoise.off").second.find("signal 15 (SIGTERM)"),
            std::string::npos)
      << slurp(results_);
}

TEST_F(BatchHostile, ABatchStoppedFromOutsideLeavesNoRowForThePairInFlight) {
  write_list({"blob4_colnoise.off", "blob4_geonoise.off"});
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::setpgid(0, 0);
    ::setenv("QM3D_DATA_DIR", test::tables_dir().c_str(), 1);
    ::setenv("QM3D_TEST_FAULT", "hang:blob4_geonoise.off", 1);
    const int devnull = ::open("/dev/null", O_WRONLY);
    ::dup2(devnull, 2);
    ::execl(QM3D_BINARY, "qm3d", "batch", list_.c_str(), "-o", results_.c_str(), "--quiet",
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::setpgid(pid, pid);
  // The first pair's row is written; the second pair's worker hangs.
  for (int i = 0; i < 6000 && read_rows(results_).by_name.size() < 1; ++i) ::usleep(20000);
  ASSERT_EQ(read_rows(results_).by_name.size(), 1u);
  ::usleep(200000);
  ::kill(-pid, SIGTERM);
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << status;
  EXPECT_EQ(read_rows(results_).by_name.count("blob4_geonoise.off"), 0u) << slurp(results_);
  const CliRun resumed = qm3d(batch("--resume"));
  EXPECT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_EQ(read_rows(results_).by_name.size(), 2u);
}

// ---- resume --------------------------------------------------------------------------------

TEST_F(BatchHostile, ResumeWithOtherSettingsIsRefusedNamingWhatDiffers) {
  write_list({"blob4_colnoise.off", "blob4_geonoise.off"});
  std::ofstream(list_, std::ios::app) << mesh("blob4_ref.off") << ",missing.off,cmdm\n";
  ASSERT_EQ(qm3d(batch()).code, 2);
  const std::string before = slurp(results_);
  EXPECT_NE(before.find(",settings\n"), std::string::npos);
  const CliRun r = qm3d(batch("--resume --scales 2"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("scales: default in " + results_.string() + ", 2 in this run"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(slurp(results_), before);
}

TEST_F(BatchHostile, ColourScaleReachesTheWorkersAndIsASetting) {
  // a.off has one colour value of 1.0000001 where b.off has 1: `auto` reads a.off as 0..255
  // (the reference's rule: nearly black), `unit` as 0..1 (clamped: the pair is identical).
  const std::string coff =
      "COFF\n4 2 0\n0 0 0 1 0.5 0.5 1\n1 0 0 0.2 0.4 0.6 1\n"
      "0 1 0 0.9 0.1 0.3 1\n1 1 0 0.3 0.3 0.3 1\n3 0 1 2\n3 1 3 2\n";
  std::string above = coff;
  above.replace(above.find("0 0 0 1 "), 8, "0 0 0 1.0000001 ");
  std::ofstream(dir_ / "a.off") << above;
  std::ofstream(dir_ / "b.off") << coff;
  std::ofstream(list_) << "reference,distorted,metric\nb.off,a.off,pcqm\n";
  const auto score = [&] {
    return csv_split(slurp(results_).substr(slurp(results_).find('\n') + 1))[3];
  };
  ASSERT_EQ(qm3d(batch("--colour-scale unit")).code, 0) << slurp(results_);
  EXPECT_EQ(score(), "0");
  EXPECT_NE(slurp(results_).find("colour-scale=unit"), std::string::npos) << slurp(results_);
  const CliRun r = qm3d(batch("--resume"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("colour-scale"), std::string::npos) << r.err;
  ASSERT_EQ(qm3d(batch("--overwrite")).code, 0) << slurp(results_);
  EXPECT_GT(std::stod(score()), 0.01);
}

TEST_F(BatchHostile, ResumeExitsNonZeroWhileErrorRowsRemain) {
  write_list({"blob4_colnoise.off"});
  std::ofstream(list_, std::ios::app) << mesh("blob4_ref.off") << ",missing.off,cmdm\n";
  ASSERT_EQ(qm3d(batch()).code, 2);
  const CliRun resumed =
      qm3d("batch '" + list_.string() + "' -o '" + results_.string() + "' --resume");
  EXPECT_EQ(resumed.code, 2);
  EXPECT_NE(resumed.err.find("1 rows of " + results_.string() + " record an error"),
            std::string::npos)
      << resumed.err;
  EXPECT_EQ(read_rows(results_).count.size(), 2u);
}

TEST_F(BatchHostile, RetryFailedReplacesTheRowsOfTheFileALinkNames) {
  write_list({"blob4_colnoise.off"});
  std::ofstream(list_, std::ios::app) << mesh("blob4_ref.off") << ",missing.off,cmdm\n";
  const fs::path real = dir_ / "real.csv";
  fs::create_symlink(real, results_);
  ASSERT_EQ(qm3d(batch("--overwrite")).code, 2);
  EXPECT_EQ(qm3d(batch("--resume --retry-failed")).code, 2);  // missing.off fails again
  EXPECT_TRUE(fs::is_symlink(results_));
  const Rows rows = read_rows(real);
  for (const auto& [key, n] : rows.count) EXPECT_EQ(n, 1) << key;
  EXPECT_EQ(rows.count.size(), 2u);
}

TEST_F(BatchHostile, ResumeOntoTheListOrAnUnrelatedFileIsRefused) {
  write_list({"blob4_colnoise.off"});
  const std::string list_text = slurp(list_);
  CliRun r = qm3d("batch '" + list_.string() + "' -o '" + list_.string() + "' --resume");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("is the list itself"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(list_), list_text);
  std::ofstream(results_) << "subject,mos\ns1,3.5\n";
  r = qm3d(batch("--resume"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("not a qm3d batch results file"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(results_), "subject,mos\ns1,3.5\n");
}

TEST_F(BatchHostile, AnInputOfTheListIsNeverTheOutput) {
  const fs::path mesh_copy = dir_ / "ref.off";
  fs::copy_file(mesh("blob4_ref.off"), mesh_copy);
  std::ofstream(list_) << "ref.off," << mesh("blob4_colnoise.off") << ",cmdm\n";
  const std::string before = slurp(mesh_copy);
  CliRun r = qm3d("batch '" + list_.string() + "' -o '" + mesh_copy.string() + "' --overwrite");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("is an input of the list (ref.off)"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(mesh_copy), before);
  // merge: the list is not the output either.
  const std::string list_text = slurp(list_);
  r = qm3d("merge '" + results_.string() + "' -o '" + list_.string() + "' --list '" +
           list_.string() + "'");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("is the list itself"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(list_), list_text);
}

TEST_F(BatchHostile, AnUnusableReportFolderIsFoundBeforeTheResultsAreTouched) {
  write_list({"blob4_colnoise.off"});
  std::ofstream(dir_ / "a_file") << "x";
  const CliRun r = qm3d(batch("--report-dir '" + (dir_ / "a_file" / "reports").string() + "'"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("cannot create the report folder"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(results_));
}

TEST_F(BatchHostile, ASecondBatchOnLockedResultsIsRefused) {
  write_list({"blob4_colnoise.off"});
  std::ofstream(list_, std::ios::app) << mesh("blob4_ref.off") << ",missing.off,cmdm\n";
  ASSERT_EQ(qm3d(batch()).code, 2);
  const std::string before = slurp(results_);
  // This test holds the lock a running batch holds.
  const int fd = ::open(results_.c_str(), O_RDONLY | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  const CliRun r = qm3d(batch("--resume --retry-failed"));
  ::close(fd);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(results_.string() + ": is being written by another qm3d batch (pid " +
                       std::to_string(::getpid()) + ")"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(slurp(results_), before);
}

// ---- lists ---------------------------------------------------------------------------------

TEST_F(BatchHostile, ListWithABomAndReorderedColumnsReadsByTheHeaderNames) {
  std::ofstream(list_) << "\xEF\xBB\xBF"
                       << "distorted,reference,metric\n"
                       << mesh("blob4_colnoise.off") << "," << mesh("blob4_ref.off") << ",cmdm\n";
  const CliRun r = qm3d(batch());
  EXPECT_EQ(r.code, 0) << r.err << slurp(results_);
  std::istringstream in(slurp(results_));
  std::string header, row, extra;
  std::getline(in, header);
  std::getline(in, row);
  EXPECT_FALSE(std::getline(in, extra)) << "more than one row: " << extra;
  const auto f = csv_split(row);
  ASSERT_GT(f.size(), 4u);
  EXPECT_EQ(f[0], mesh("blob4_ref.off"));
  EXPECT_EQ(f[1], mesh("blob4_colnoise.off"));
  EXPECT_EQ(f[4], "ok");
}

TEST_F(BatchHostile, ListWithAnUnknownColumnIsRefused) {
  std::ofstream(list_) << "reference,distorted,weight\na.off,b.off,2\n";
  const CliRun r = qm3d(batch());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("unknown column \"weight\""), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(results_));
}

// ---- merge ---------------------------------------------------------------------------------

TEST_F(BatchHostile, MergeCountsANonNumberScoreAsAnError) {
  write_list({"blob4_colnoise.off"});
  ASSERT_EQ(qm3d(batch()).code, 0);
  std::string text = slurp(results_);
  const auto first_row = text.find('\n') + 1;
  auto f = csv_split(text.substr(first_row, text.find('\n', first_row) - first_row));
  f[3] = "garbage";
  std::string row;
  for (const auto& field : f) row += (row.empty() ? "" : ",") + csv_field(field);
  const fs::path shard = dir_ / "shard.csv", merged = dir_ / "merged.csv";
  std::ofstream(shard) << text.substr(0, first_row) << row << "\n";
  const CliRun r = qm3d("merge '" + shard.string() + "' -o '" + merged.string() + "' --list '" +
                        list_.string() + "'");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("\"garbage\" is not a score"), std::string::npos) << r.err;
  const Rows rows = read_rows(merged);
  EXPECT_EQ(rows.by_name.at("blob4_colnoise.off").first, "error");
}

TEST_F(BatchHostile, MergePartialGoesOnWithoutAMissingShard) {
  write_list({"blob4_colnoise.off"});
  ASSERT_EQ(qm3d(batch()).code, 0);
  const fs::path missing = dir_ / "OUT_1.csv", merged = dir_ / "merged.csv";
  const CliRun r = qm3d("merge '" + results_.string() + "' '" + missing.string() + "' -o '" +
                        merged.string() + "' --list '" + list_.string() + "' --partial");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find(missing.string() + ": no such file"), std::string::npos) << r.err;
  EXPECT_EQ(read_rows(merged).by_name.at("blob4_colnoise.off").first, "ok");
  // Without --partial a missing shard stays an error.
  EXPECT_EQ(qm3d("merge '" + results_.string() + "' '" + missing.string() + "' -o '" +
                 (dir_ / "m2.csv").string() + "' --list '" + list_.string() + "'")
                .code,
            2);
  EXPECT_FALSE(fs::exists(dir_ / "m2.csv"));
}

}  // namespace
}  // namespace qm3d
