// The tools against the second hostile probe (issue 37, items 3 and 6): views on a full disk,
// batch's views per pair, merge and PSNR's inf, --pair-timeout's huge and NaN values, and the
// smaller findings of eval, train, psnr, compare and report. Each test failed before its fix.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli_runner.h"
#include "qm3d/common/result_io.h"
#include "test_paths.h"

namespace qm3d {
namespace {

namespace fs = std::filesystem;
using test::CliRun;
using test::slurp;

class ToolsHostile : public ::testing::Test {
 public:
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string file(const std::string& name, const std::string& content) const {
    std::ofstream(dir_ / name, std::ios::binary) << content;
    return path(name);
  }

 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_tools_hostile_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "io");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs in the repository's data folder (meshes/, clouds/).
  CliRun qm3d(const std::string& args, const std::string& env = "") {
    return test::run_qm3d(args, test::source_dir() / "data", dir_ / "io",
                          "QM3D_DATA_DIR='" + test::tables_dir().string() + "' " + env);
  }
  // A batch list of blob3_ref against each of `distorted`, all scored with `metric`.
  std::string list(const std::vector<std::string>& distorted, const std::string& metric) const {
    std::string text = "reference,distorted,metric\n";
    const std::string meshes = (test::source_dir() / "data" / "meshes").string() + "/";
    for (const auto& d : distorted) {
      text += meshes + "blob3_ref.off," + meshes + d + "," + metric + "\n";
    }
    return file("list.csv", text);
  }

  fs::path dir_;
};

// ---- item 3: data lost, changed or half-written
// --------------------------------------------------

// A file size limit (ulimit -f, SIGXFSZ ignored) makes every write past 1 KiB fail as a full
// disk does: the views were written with stbi_write_png, which reports no fwrite error, and
// ibsm exited 0 with truncated PNGs.
TEST_F(ToolsHostile, ViewsOnAFullDiskFailNamingTheFileAndLeaveNoPartialPng) {
  const std::string views = path("views");
  const CliRun r = qm3d(
      "ibsm meshes/blob3_ref.off meshes/blob3_geonoise.off --resolution 256 "
      "--views 2 --no-ssim --save-views " +
          views,
      "ulimit -f 1; trap '' XFSZ;");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find(views + "/view_0"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("write failed"), std::string::npos) << r.err;
  for (const auto& e : fs::directory_iterator(views)) {
    ADD_FAILURE() << "left behind: " << e.path() << " (" << fs::file_size(e.path()) << " bytes)";
  }
  // Without the limit the same views are written whole.
  const CliRun ok = qm3d(
      "ibsm meshes/blob3_ref.off meshes/blob3_geonoise.off --resolution 256 "
      "--views 2 --no-ssim --save-views " +
      views);
  ASSERT_EQ(ok.code, 0) << ok.err;
  EXPECT_GT(fs::file_size(views + "/view_01_distorted.png"), 1024u);
}

// Every pair wrote the same view_NN_*.png: one folder per pair, named as its report.
TEST_F(ToolsHostile, BatchSavesEachPairsViewsInItsOwnFolder) {
  const std::string views = path("views"), results = path("results.csv");
  const CliRun r = qm3d("batch " + list({"blob3_geonoise.off", "blob3_colnoise.off"}, "ibsm") +
                        " -o " + results +
                        " --quiet --jobs 2 --resolution 64 --views 2 "
                        "--no-ssim --save-views " +
                        views);
  ASSERT_EQ(r.code, 0) << r.err << slurp(results);
  std::map<std::string, int> pngs;  // folder -> PNG files
  for (const auto& e : fs::recursive_directory_iterator(views)) {
    if (e.path().extension() == ".png") ++pngs[e.path().parent_path().filename().string()];
  }
  ASSERT_EQ(pngs.size(), 2u);
  for (const auto& [folder, count] : pngs) {
    EXPECT_EQ(count, 4) << folder;
    EXPECT_EQ(folder.rfind("blob3_", 0), 0u) << folder;
    EXPECT_NE(folder.find("_vs_blob3_ref-"), std::string::npos) << folder;
  }
}

// PSNR of identical geometry is inf, which batch writes and documents: merge made it an error
// row (exit code 2), so sharded results differed from unsharded ones.
TEST_F(ToolsHostile, MergeKeepsTheInfOfIdenticalInputs) {
  const std::string results = path("results.csv"), merged = path("merged.csv");
  const std::string listed = list({"blob3_ref.off", "blob3_geonoise.off"}, "psnr");
  ASSERT_EQ(qm3d("batch " + listed + " -o " + results + " --quiet --grid-size 128").code, 0);
  ASSERT_NE(slurp(results).find(",psnr,inf,"), std::string::npos) << slurp(results);
  const CliRun m = qm3d("merge " + results + " -o " + merged + " --list " + listed);
  EXPECT_EQ(m.code, 0) << m.err;
  EXPECT_EQ(slurp(merged), slurp(results));
}

// --pair-timeout 1e10 overflowed the int64 nanoseconds of the deadline (every pair "timed out"
// at once) and nan was taken as no limit: huge is no limit, nan is refused.
TEST_F(ToolsHostile, PairTimeoutHugeIsNoLimitAndNanIsRefused) {
  const std::string results = path("results.csv");
  const std::string listed = list({"blob3_geonoise.off"}, "cmdm");
  for (const char* huge : {"1e10", "1e300", "inf"}) {
    const CliRun r = qm3d("batch " + listed + " -o " + results +
                          " --quiet --overwrite "
                          "--pair-timeout " +
                          huge);
    EXPECT_EQ(r.code, 0) << huge << ": " << r.err << slurp(results);
    EXPECT_EQ(slurp(results).find("timed out"), std::string::npos) << huge;
  }
  const CliRun nan = qm3d("batch " + listed + " -o " + path("nan.csv") + " --pair-timeout nan");
  EXPECT_NE(nan.code, 0);
  EXPECT_NE(nan.err.find("--pair-timeout"), std::string::npos) << nan.err;
  EXPECT_FALSE(fs::exists(path("nan.csv")));
}

// ---- item 6: the smaller findings --------------------------------------------------------------

TEST_F(ToolsHostile, MeshPsnrSaysWhereItsPeakComesFrom) {
  const CliRun r = qm3d("psnr meshes/blob3_ref.off meshes/blob3_geonoise.off --grid-size 128");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out.find("(given)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(diagonal of the reference's sampled cloud's box"), std::string::npos)
      << r.out;
  const CliRun given =
      qm3d("psnr meshes/blob3_ref.off meshes/blob3_geonoise.off --grid-size 128 --peak 2");
  ASSERT_EQ(given.code, 0) << given.err;
  EXPECT_NE(given.out.find("peak 2 (given)"), std::string::npos) << given.out;
}

// compare and report do not run ibsm: its options were accepted and ignored.
TEST_F(ToolsHostile, CompareAndReportRefuseTheOptionsOfMetricsTheyDoNotRun) {
  for (const std::string command : {"compare", "report"}) {
    for (const std::string option :
         {"--save-views " + path("v"), std::string("--views 4"), std::string("--resolution 64")}) {
      const std::string out = command == "report" ? " -o " + path("r.html") : "";
      const CliRun r =
          qm3d(command + " meshes/blob3_ref.off meshes/blob3_geonoise.off" + out + " " + option);
      EXPECT_NE(r.code, 0) << command << " " << option;
      EXPECT_NE(r.err.find(option.substr(0, option.find(' '))), std::string::npos) << r.err;
    }
  }
  EXPECT_FALSE(fs::exists(path("v")));
  EXPECT_FALSE(fs::exists(path("r.html")));
}

// Eval's subjective files: 6 stimuli, two metrics, SD and n, individual scores.
struct EvalFiles {
  std::string scores, mos;
};

EvalFiles eval_files(ToolsHostile& t, std::size_t stimuli = 6) {
  std::string scores = "stimulus,psnr,cmdm\n", mos = "stimulus,mos,sd,n\n";
  for (std::size_t i = 0; i < stimuli; ++i) {
    const std::string s = "s" + std::to_string(i);
    const double q = 1 + 0.7 * static_cast<double>(i) + 0.1 * static_cast<double>(i % 2);
    scores += s + "," + std::to_string(20 + 3 * q) + "," + std::to_string(0.5 - 0.08 * q) + "\n";
    mos += s + "," + std::to_string(q) + ",0.4,20\n";
  }
  return {t.file("scores.csv", scores), t.file("mos.csv", mos)};
}

TEST_F(ToolsHostile, LowerIsBetterNamingNoMetricIsRefused) {
  const EvalFiles f = eval_files(*this);
  const CliRun typo = qm3d("eval " + f.scores + " " + f.mos +
                           " --scores-column psnr,cmdm "
                           "--sd-column sd --n-column n --bootstrap 0 --lower-is-better cmmd");
  EXPECT_EQ(typo.code, 2) << typo.err;
  EXPECT_NE(typo.err.find("--lower-is-better cmmd: no such metric"), std::string::npos) << typo.err;
  const CliRun right = qm3d("eval " + f.scores + " " + f.mos +
                            " --scores-column psnr,cmdm "
                            "--sd-column sd --n-column n --bootstrap 0 --lower-is-better cmdm");
  EXPECT_EQ(right.code, 0) << right.err;
  // One column (no protocol): the name must be that column.
  const CliRun single = qm3d("eval " + f.scores + " " + f.mos +
                             " --scores-column psnr "
                             "--bootstrap 0 --lower-is-better othr");
  EXPECT_EQ(single.code, 2) << single.err;
  EXPECT_NE(single.err.find("--lower-is-better othr"), std::string::npos) << single.err;
}

TEST_F(ToolsHostile, RawScoresThatAreNotNumbersOrAllTheSame) {
  const EvalFiles f = eval_files(*this);
  std::string raw = "stimulus,observer,score\n";
  for (int i = 0; i < 6; ++i) {
    for (int o = 0; o < 3; ++o) raw += "s" + std::to_string(i) + ",o" + std::to_string(o) + ",3\n";
  }
  // All the same: no significantly different pair, a data error (exit 2) naming the file.
  const std::string constant = file("constant.csv", raw);
  const CliRun c = qm3d("eval " + f.scores + " " + f.mos + " --scores-column psnr,cmdm --raw " +
                        constant + " --bootstrap 0");
  EXPECT_EQ(c.code, 2) << c.err;
  EXPECT_NE(c.err.find(constant + " (--raw): 0 of 36 pairs are significantly different"),
            std::string::npos)
      << c.err;
  // NaN is not "an empty score".
  const std::string with_nan = file("nan.csv", raw + "s0,o9,nan\n");
  const CliRun n = qm3d("eval " + f.scores + " " + f.mos + " --scores-column psnr,cmdm --raw " +
                        with_nan + " --bootstrap 0");
  EXPECT_EQ(n.code, 2) << n.err;
  EXPECT_NE(n.err.find(with_nan + ":20: the score \"nan\" is not a number"), std::string::npos)
      << n.err;
}

TEST_F(ToolsHostile, APairOfAStimulusWithItselfIsRefused) {
  const EvalFiles f = eval_files(*this);
  const std::string pairs = file("pairs.csv", "first,second,label\ns1,s0,1\ns2,s2,0\ns3,s1,1\n");
  const CliRun r = qm3d("eval " + f.scores + " " + f.mos + " --scores-column psnr,cmdm --pairs " +
                        pairs + " --bootstrap 0");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find(pairs + ":3: stimulus \"s2\" is paired with itself"), std::string::npos)
      << r.err;
}

// 4 stimuli (VMAF's raw-score tests) with a mapping of 2 parameters or none: correlations are
// defined; the logistic's 5 stimuli are needed only where it is used.
TEST_F(ToolsHostile, FourStimuliAreEnoughWithoutTheLogistic) {
  const EvalFiles f = eval_files(*this, 4);
  for (const char* mapping : {"none", "linear"}) {
    const CliRun r = qm3d("eval " + f.scores + " " + f.mos +
                          " --scores-column psnr,cmdm "
                          "--bootstrap 50 --json --mapping " +
                          std::string(mapping));
    ASSERT_EQ(r.code, 0) << mapping << ": " << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["stimuli"], 4);
    EXPECT_DOUBLE_EQ(j["metrics"]["psnr"]["statistics"]["srocc"]["value"].get<double>(), 1.0);
  }
  const CliRun logistic = qm3d("eval " + f.scores + " " + f.mos +
                               " --scores-column psnr,cmdm --bootstrap 0 --mapping logistic4");
  EXPECT_EQ(logistic.code, 2) << logistic.err;
  const EvalFiles two = eval_files(*this, 2);
  const CliRun too_few = qm3d("eval " + two.scores + " " + two.mos +
                              " --scores-column psnr,cmdm --bootstrap 0 --mapping none");
  EXPECT_EQ(too_few.code, 2) << too_few.err;
  EXPECT_NE(too_few.err.find("2 stimuli, at least 3 needed"), std::string::npos) << too_few.err;
}

// Features near 1e300 overflow the standardisation: said so, not "the scores are constant".
TEST_F(ToolsHostile, TrainOnHugeFeaturesSaysTheyOverflow) {
  std::string features = "stimulus,source,f1,f2,f3,f4,f5,f6,f7,f8\n", mos = "stimulus,mos\n";
  for (int i = 0; i < 12; ++i) {
    const std::string s = "s" + std::to_string(i);
    features += s + ",g" + std::to_string(i % 3);
    for (int k = 0; k < 8; ++k) features += "," + std::to_string(1 + i + k) + "e300";
    features += "\n";
    mos += s + "," + std::to_string(1 + 0.3 * i) + "\n";
  }
  const CliRun r = qm3d("train " + file("f.csv", features) + " " + file("m.csv", mos) +
                        " --metric pcqm --subset f1 --group-by source");
  EXPECT_NE(r.code, 0);
  EXPECT_EQ(r.err.find("constant"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("feature f1 has values too large to standardise"), std::string::npos)
      << r.err;
}

// A PCD without colours reads as a colourless PLY does.
TEST_F(ToolsHostile, PsnrWithoutColourTakesAColourlessPcd) {
  std::ostringstream a, b;
  a << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 27\nHEIGHT 1\n"
       "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 27\nDATA ascii\n";
  b << a.str();
  for (int i = 0; i < 27; ++i) {
    a << i % 3 << ' ' << i / 3 % 3 << ' ' << i / 9 << "\n";
    b << i % 3 + 0.01 * (i % 2) << ' ' << i / 3 % 3 << ' ' << i / 9 << "\n";
  }
  const std::string pa = file("a.pcd", a.str()), pb = file("b.pcd", b.str());
  const CliRun r = qm3d("psnr " + pa + " " + pb + " --no-color");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("PSNR = ", 0), 0u) << r.out;
  // A metric that needs colours still says what the PCD lacks.
  const CliRun pcqm = qm3d("pcqm " + pa + " " + pb);
  EXPECT_EQ(pcqm.code, 2);
  EXPECT_NE(pcqm.err.find("no vertex colours"), std::string::npos) << pcqm.err;
  EXPECT_NE(pcqm.err.find("'rgb' or 'rgba' PCD field"), std::string::npos) << pcqm.err;
}

}  // namespace
}  // namespace qm3d
