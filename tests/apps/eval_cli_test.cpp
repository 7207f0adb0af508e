// End-to-end tests of `qm3d eval`, `qm3d train` and `--model`, running the built binary.
#include <gtest/gtest.h>
#include <stb/stb_image.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <sstream>

#include "qm3d/evaluation/evaluation.h"
#include "qm3d/common/pooling.h"
#include "cli_runner.h"
#include "test_paths.h"

namespace qm3d {
namespace {
using namespace qm3d::evaluation;  // the evaluation toolkit (qm3d/evaluation/)

namespace fs = std::filesystem;
using test::CliRun;
using test::slurp;
using nlohmann::json;

double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

double normal(std::mt19937_64& rng) {
  const double u1 = 1 - uniform01(rng), u2 = uniform01(rng);
  return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
}

std::string exact(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

fs::path mos_dir() { return test::shared_data() / "mos"; }
std::string basics_scores() { return (mos_dir() / "basics_pcqm_predictions.csv").string(); }
std::string basics_mos() { return (mos_dir() / "basics_mos.csv").string(); }

class EvalCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("qm3d_eval_cli_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "cwd");
    fs::create_directories(dir_ / "io");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs qm3d with `args` (after `env`, e.g. "PATH=/none") in an empty working directory,
  // checked to stay empty.
  CliRun qm3d(const std::string& args, const std::string& env = "") {
    const CliRun r = test::run_qm3d(args, dir_ / "cwd", dir_ / "io", env);
    EXPECT_TRUE(fs::is_empty(dir_ / "cwd"))
        << "qm3d " << args << " wrote into the working directory";
    return r;
  }

  fs::path file(const std::string& name, const std::string& content) {
    const fs::path p = dir_ / "io" / name;
    std::ofstream(p, std::ios::binary) << content;
    return p;
  }

  fs::path dir_;
};

// ---- eval ----------------------------------------------------------------------------------

TEST_F(EvalCli, BasicsReproducesThePublishedCorrelations) {
  const CliRun r = qm3d("eval " + basics_scores() + " " + basics_mos() + " --json --bootstrap 200");
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["stimuli"], 1140);
  EXPECT_EQ(j["scores"]["key"], "ppc");
  EXPECT_EQ(j["scores"]["column"], "predictions");
  EXPECT_EQ(j["mos"]["key"], "stimulus");
  const json& s = j["statistics"];
  // Acceptance (issue 9): Spearman -0.788 and plain Pearson -0.837, +-0.001.
  EXPECT_NEAR(s["srocc"]["value"].get<double>(), -0.788, 0.001);
  EXPECT_NEAR(s["plcc"]["value"].get<double>(), -0.837, 0.001);
  // shared/data/README.md gives -0.7878 and -0.8368.
  EXPECT_NEAR(s["srocc"]["value"].get<double>(), -0.7878, 5e-5);
  EXPECT_NEAR(s["plcc"]["value"].get<double>(), -0.8368, 5e-5);
  EXPECT_GT(std::fabs(s["plcc_logistic"]["value"].get<double>()),
            std::fabs(s["plcc"]["value"].get<double>()));
  EXPECT_TRUE(j["logistic"]["converged"].get<bool>());
  const auto ci = s["srocc"]["ci95"];
  EXPECT_LT(ci[0].get<double>(), -0.7878);
  EXPECT_GT(ci[1].get<double>(), -0.7878);
  EXPECT_EQ(j["bootstrap"]["used"], 200);
  EXPECT_FALSE(s.contains("outlier_ratio"));
  // The 360 predictions without a MOS are reported, not silently dropped.
  EXPECT_EQ(j["unmatched"]["scores"]["count"], 360);
  EXPECT_EQ(j["unmatched"]["scores"]["first"].size(), 5u);
  EXPECT_EQ(j["unmatched"]["mos"]["count"], 0);
  EXPECT_NE(r.err.find("basics_pcqm_predictions.csv: 360 rows have no partner in"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find(j["unmatched"]["scores"]["first"][0].get<std::string>()), std::string::npos);
}

TEST_F(EvalCli, TextAndCsvOutputsAreDeterministic) {
  const std::string args = "eval " + basics_scores() + " " + basics_mos() + " --bootstrap 50 -q";
  const CliRun a = qm3d(args), b = qm3d(args);
  ASSERT_EQ(a.code, 0) << a.err;
  EXPECT_EQ(a.out, b.out);
  EXPECT_EQ(a.err, "");  // -q
  EXPECT_NE(a.out.find("1140 stimuli"), std::string::npos) << a.out;
  EXPECT_NE(a.out.find("SROCC               -0.7878"), std::string::npos) << a.out;
  EXPECT_NE(qm3d(args + " --seed 2").out, a.out);
  const fs::path csv = dir_ / "io" / "stats.csv";
  ASSERT_EQ(qm3d(args + " --csv -o " + csv.string()).code, 0);
  const std::string text = slurp(csv);
  EXPECT_EQ(text.rfind("statistic,value,ci95_low,ci95_high\nstimuli,1140,,\nplcc,-0.83683", 0), 0u)
      << text;
  EXPECT_NE(text.find("\nrmse_logistic,0.497"), std::string::npos) << text;
}

TEST_F(EvalCli, OutlierRatioFromTheMosConfidenceIntervals) {
  // Scores made up for the CMDM dataset's MOS (a noisy decreasing function of it).
  const fs::path mos = mos_dir() / "cmdm_vertexcolor_db_All_Stimuli_MOS_and_MLE.csv";
  std::ifstream in(mos);
  std::string line;
  std::getline(in, line);
  std::mt19937_64 rng(5);
  std::ostringstream scores;
  scores << "stimulus,score\n";
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string key, mos_cell;
    std::getline(fields, key, ',');
    for (int c = 1; c < 8; ++c) std::getline(fields, mos_cell, ',');  // MOS: column 8
    scores << key << "," << exact(0.2 / (std::stod(mos_cell) + 0.3 * normal(rng) + 0.5)) << "\n";
  }
  const fs::path s = file("cmdm_scores.csv", scores.str());
  const CliRun r = qm3d("eval " + s.string() + " " + mos.string() +
                        " --mos-column MOS --ci-column CI --bootstrap 100 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["stimuli"], 480);
  EXPECT_EQ(j["mos"]["key"], "Stimuli");
  EXPECT_EQ(j["mos"]["ci_column"], "CI");
  const double ratio = j["statistics"]["outlier_ratio"]["value"].get<double>();
  EXPECT_GT(ratio, 0.0);
  EXPECT_LT(ratio, 1.0);
  EXPECT_LT(j["statistics"]["plcc"]["value"].get<double>(), -0.5);
}

TEST_F(EvalCli, StemMatchesBatchPathsToStimulusNames) {
  const fs::path scores = file("results.csv",
                               "reference,distorted,metric,score,status\n"
                               "/r/a.ply,/d/s1.ply,pcqm,0.1,ok\n/r/a.ply,/d/s2.ply,pcqm,0.2,ok\n"
                               "/r/a.ply,/d/s3.ply,pcqm,0.35,ok\n/r/a.ply,/d/s4.ply,pcqm,,error\n"
                               "/r/a.ply,/d/s5.ply,pcqm,0.5,ok\n/r/a.ply,/d/s6.ply,pcqm,0.6,ok\n");
  const fs::path mos =
      file("mos.csv", "name,MOS\ns1,4.9\ns2,4.1\ns3,3.2\ns4,3\ns5,1.5\ns6,1.1\ns7,2\n");
  // No key matches whole: matched by file stem, with a note saying so.
  const CliRun plain = qm3d("eval " + scores.string() + " " + mos.string() + " --json");
  ASSERT_EQ(plain.code, 0) << plain.err;
  EXPECT_NE(plain.err.find("matching them by file stem (as --stem)"), std::string::npos)
      << plain.err;
  EXPECT_EQ(json::parse(plain.out)["stimuli"], 5);
  EXPECT_EQ(json::parse(plain.out)["key_match"], "file stem");
  // Nothing matches either way: the error shows one key of each side and names --stem.
  const fs::path other = file("other.csv", "name,MOS\nx1,4.9\nx2,4.1\n");
  const CliRun none = qm3d("eval " + scores.string() + " " + other.string());
  EXPECT_EQ(none.code, 2);
  EXPECT_NE(none.err.find("(key \"distorted\", e.g. \"/d/s1.ply\")"), std::string::npos)
      << none.err;
  EXPECT_NE(none.err.find("(key \"name\", e.g. \"x1\")"), std::string::npos) << none.err;
  EXPECT_NE(none.err.find("--stem"), std::string::npos) << none.err;
  const CliRun r =
      qm3d("eval " + scores.string() + " " + mos.string() + " --stem --json --bootstrap 20");
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["scores"]["key"], "distorted");
  EXPECT_EQ(j["scores"]["column"], "score");
  EXPECT_EQ(j["stimuli"], 5);
  EXPECT_EQ(j["missing_values"]["first"], json::array({"s4"}));  // the failed pair
  EXPECT_EQ(j["unmatched"]["mos"]["first"], json::array({"s7"}));
  EXPECT_DOUBLE_EQ(j["statistics"]["srocc"]["value"].get<double>(), -1.0);
  EXPECT_NE(r.err.find("1 stimuli left out (empty or NaN score, MOS or CI): s4"), std::string::npos)
      << r.err;
}

// The orientation of a score column comes from the metric the rows name (psnr: a quality, its
// d1_mse a distortion; cmdm: a distortion), or --orientation; a column ranking the other way is
// warned about; an infinite PSNR (unchanged geometry) is left out with a warning.
TEST_F(EvalCli, OrientationFromTheMetricColumnOrTheOption) {
  std::string psnr = "reference,distorted,metric,score,status,d1_mse\n";
  const double db[] = {20, 24, 29, 33, 38, 41};
  for (int k = 0; k < 6; ++k) {
    psnr += "r.ply,s" + std::to_string(k + 1) + ".ply,psnr," + exact(db[k]) + ",ok," +
            exact(std::pow(10.0, -db[k] / 10)) + "\n";
  }
  psnr += "r.ply,s7.ply,psnr,inf,ok,0\n";
  const fs::path scores = file("psnr.csv", psnr);
  const fs::path mos =
      file("mos.csv", "distorted,mos\ns1.ply,1.2\ns2.ply,2.1\ns3.ply,2.9\ns4.ply,3.8\n"
                      "s5.ply,4.1\ns6.ply,4.6\ns7.ply,4.9\n");
  const std::string base = "eval " + scores.string() + " " + mos.string() + " --bootstrap 0";

  const CliRun q = qm3d(base + " --json");
  ASSERT_EQ(q.code, 0) << q.err;
  json j = json::parse(q.out);
  EXPECT_EQ(j["orientation"]["higher_is_better"], true);
  EXPECT_EQ(j["orientation"]["from"], "metric column: psnr");
  EXPECT_EQ(j["orientation"]["agrees"], true);
  EXPECT_EQ(j["stimuli"], 6);
  EXPECT_EQ(j["infinite_scores"]["first"], json::array({"s7.ply"}));
  EXPECT_DOUBLE_EQ(j["statistics"]["srocc"]["value"].get<double>(), 1.0);
  EXPECT_NE(q.err.find("1 stimuli left out (infinite score"), std::string::npos) << q.err;
  EXPECT_EQ(q.err.find("SROCC"), std::string::npos) << q.err;

  const CliRun mse = qm3d(base + " --scores-column d1_mse --json");
  ASSERT_EQ(mse.code, 0) << mse.err;
  j = json::parse(mse.out);
  EXPECT_EQ(j["orientation"]["higher_is_better"], false);
  EXPECT_EQ(j["orientation"]["agrees"], true);
  EXPECT_EQ(j["stimuli"], 7);  // the zero MSE is a value

  const CliRun text = qm3d(base);
  ASSERT_EQ(text.code, 0) << text.err;
  EXPECT_NE(text.out.find("orientation: quality (higher is better), from metric column: psnr"),
            std::string::npos)
      << text.out;

  // Told it is a distortion, the PSNR ranks the other way: a warning naming file and column.
  const CliRun wrong = qm3d(base + " --orientation distortion --json");
  ASSERT_EQ(wrong.code, 0) << wrong.err;
  j = json::parse(wrong.out);
  EXPECT_EQ(j["orientation"]["from"], "--orientation");
  EXPECT_EQ(j["orientation"]["agrees"], false);
  EXPECT_NE(wrong.err.find(scores.string() + ": column \"score\" is a distortion (lower is "
                                             "better) but SROCC with mos is 1.0000"),
            std::string::npos)
      << wrong.err;

  // No metric column: unknown, no warning; a bad value is refused.
  const fs::path bare = file("bare.csv", "distorted,score\ns1.ply,1\ns2.ply,2\ns3.ply,3\n"
                                         "s4.ply,4\ns5.ply,5\ns6.ply,6\n");
  const CliRun unknown = qm3d("eval " + bare.string() + " " + mos.string() + " --bootstrap 0 --json");
  ASSERT_EQ(unknown.code, 0) << unknown.err;
  EXPECT_TRUE(json::parse(unknown.out)["orientation"]["higher_is_better"].is_null());
  EXPECT_EQ(qm3d(base + " --orientation up").code, 1);
}

// ---- several metrics, Krasula's analysis -----------------------------------------------------

fs::path evaluation_dir() { return test::reference_dir() / "evaluation"; }

// The reference CSVs of ../shared/data/reference/evaluation as rows of named cells.
std::vector<std::map<std::string, std::string>> reference_rows(const std::string& name) {
  std::ifstream in(evaluation_dir() / name);
  std::string line;
  std::getline(in, line);
  const auto split = [](const std::string& l) {
    std::vector<std::string> cells(1);
    bool quoted = false;
    for (char c : l) {
      if (c == '"') quoted = !quoted;
      else if (c == ',' && !quoted) cells.emplace_back();
      else cells.back() += c;
    }
    return cells;
  };
  const std::vector<std::string> header = split(line);
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    const auto cells = split(line);
    std::map<std::string, std::string> r;
    for (std::size_t c = 0; c < header.size() && c < cells.size(); ++c) r[header[c]] = cells[c];
    rows.push_back(r);
  }
  return rows;
}

void expect_rel(double got, double expected, double tol, const std::string& what) {
  EXPECT_NEAR(got, expected, tol * std::fabs(expected)) << what;
}

// Every per-metric and pairwise value VMAF's code gives on the Toyama vector, from the tool's
// JSON of m1..m5 against the table's MOS, SD and n.
void expect_toyama_vmaf_values(const json& j) {
  EXPECT_EQ(j["krasula"]["different"], 11121);
  EXPECT_EQ(j["krasula"]["similar"], 2907);
  for (const auto& e : reference_rows("toyama_vmaf_computed_per_metric.csv")) {
    const json& k = j["metrics"]["m" + e.at("metric")]["krasula"];
    const std::string id = "m" + e.at("metric");
    expect_rel(k["auc_ds"], std::stod(e.at("AUC_DS")), 1e-12, id + " AUC_DS");
    expect_rel(k["auc_bw"], std::stod(e.at("AUC_BW")), 1e-12, id + " AUC_BW");
    expect_rel(k["c0"], std::stod(e.at("CC_0")), 1e-12, id + " C0");
    expect_rel(k["thr"], std::stod(e.at("THR_numpy")), 1e-12, id + " THR");
    expect_rel(k["thr_prctile"], std::stod(e.at("THR_prctile")), 1e-12, id + " THR_prctile");
    expect_rel(k["se_ds"], std::stod(e.at("SE_DS_DeLong")), 1e-12, id + " SE_DS");
    expect_rel(k["se_bw"], std::stod(e.at("SE_BW_DeLong")), 1e-12, id + " SE_BW");
  }
  std::map<std::string, double> p;
  for (const json& c : j["comparisons"]) {
    p[c["a"].get<std::string>() + c["b"].get<std::string>() + c["test"].get<std::string>()] =
        c["p"].is_null() ? NAN : c["p"].get<double>();
  }
  EXPECT_EQ(p.size(), 50u);  // 10 pairs x (fisher_z_plcc, f_rmse, delong_auc_ds, delong_auc_bw, c0)
  for (const auto& e : reference_rows("toyama_vmaf_computed_pairwise.csv")) {
    if (e.at("metric_a") == e.at("metric_b")) continue;
    const std::string ab = "m" + e.at("metric_a") + "m" + e.at("metric_b");
    EXPECT_NEAR(p.at(ab + "delong_auc_ds"), std::stod(e.at("pDS_DL")), 1e-9) << ab;
    EXPECT_NEAR(p.at(ab + "delong_auc_bw"), std::stod(e.at("pBW_DL")), 1e-9) << ab;
    EXPECT_NEAR(p.at(ab + "c0"), std::stod(e.at("pCC0_b")), 1e-9) << ab;
  }
}

// "Is the MOS column a DMOS?" only on evidence: every metric of known orientation clearly ranks
// the stimuli the other way. One metric correlating poorly, or one among others that agree, is
// no reason.
TEST_F(EvalCli, DmosWarningOnlyWhenEveryOrientedMetricDisagrees) {
  const double mos_values[] = {1.1, 1.9, 2.6, 3.2, 3.8, 4.4, 4.9, 2.2};
  const double weak_psnr[] = {30, 29, 33, 24, 31, 26, 24.5, 28};  // SROCC -0.43: poor
  std::string weak = "reference,distorted,metric,score,status\n";
  std::string both = weak, one = weak, mos = "distorted,mos\n";
  for (int k = 0; k < 8; ++k) {
    const std::string d = "r.ply,s" + std::to_string(k) + ".ply,";
    weak += d + "psnr," + exact(weak_psnr[k]) + ",ok\n";
    // A DMOS-like MOS: the PSNR falls and the CMDM rises as the MOS rises.
    both += d + "psnr," + exact(40 - 2 * mos_values[k]) + ",ok\n";
    both += d + "cmdm," + exact(0.1 * mos_values[k]) + ",ok\n";
    one += d + "psnr," + exact(20 + 2 * mos_values[k]) + ",ok\n";
    one += d + "cmdm," + exact(0.1 * mos_values[k]) + ",ok\n";
    mos += "s" + std::to_string(k) + ".ply," + exact(mos_values[k]) + "\n";
  }
  const fs::path m = file("mos.csv", mos);
  const std::string opts = " --bootstrap 0 --json";
  const CliRun poor = qm3d("eval " + file("weak.csv", weak).string() + " " + m.string() + opts);
  ASSERT_EQ(poor.code, 0) << poor.err;
  EXPECT_EQ(poor.err.find("DMOS"), std::string::npos) << poor.err;
  const CliRun mixed = qm3d("eval " + file("one.csv", one).string() + " " + m.string() + opts);
  ASSERT_EQ(mixed.code, 0) << mixed.err;
  EXPECT_EQ(mixed.err.find("DMOS"), std::string::npos) << mixed.err;
  const CliRun dmos = qm3d("eval " + file("both.csv", both).string() + " " + m.string() + opts);
  ASSERT_EQ(dmos.code, 0) << dmos.err;
  EXPECT_NE(dmos.err.find("every metric of known orientation ranks the stimuli the other way"),
            std::string::npos)
      << dmos.err;
  EXPECT_NE(dmos.err.find("is the MOS column a DMOS"), std::string::npos) << dmos.err;
}

TEST_F(EvalCli, KrasulaOnTheToyamaVectorsFromMosSdAndN) {
  const std::string table = (evaluation_dir() / "toyama_stimuli_5metrics.csv").string();
  const CliRun r = qm3d("eval " + table + " " + table +
                        " --scores-key stimulus --scores-column m1,m2,m3,m4,m5 --mos-column MOS "
                        "--sd-column SD --n-column n --bootstrap 0 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["stimuli"], 168);
  expect_toyama_vmaf_values(j);
  EXPECT_NE(j["metrics"]["m1"]["orientation"]["from"].get<std::string>().find("assumed"),
            std::string::npos);
  // The same labels given as a file of pairs (VMAF's signif): the same values.
  std::string pairs = "first,second,label\n";
  for (const auto& e : reference_rows("toyama_vmaf_pairs.csv")) {
    pairs += e.at("first") + "," + e.at("second") + "," + e.at("signif") + "\n";
  }
  const fs::path pf = file("pairs.csv", pairs);
  const CliRun given = qm3d("eval " + table + " " + table +
                            " --scores-key stimulus --scores-column m1,m2,m3,m4,m5 --mos-column "
                            "MOS --pairs " + pf.string() + " --bootstrap 0 --json");
  ASSERT_EQ(given.code, 0) << given.err;
  expect_toyama_vmaf_values(json::parse(given.out));
  // Text and CSV carry the same analysis.
  const CliRun text = qm3d("eval " + table + " " + table +
                           " --scores-key stimulus --scores-column m1,m2 --mos-column MOS "
                           "--sd-column SD --n-column n --bootstrap 0");
  ASSERT_EQ(text.code, 0) << text.err;
  EXPECT_NE(text.out.find("Krasula: 11121 different (5520 first better), 2907 similar of 14028"),
            std::string::npos)
      << text.out;
  EXPECT_NE(text.out.find("0.595422"), std::string::npos) << text.out;
  const CliRun csv = qm3d("eval " + table + " " + table +
                          " --scores-key stimulus --scores-column m1,m2 --mos-column MOS "
                          "--sd-column SD --n-column n --bootstrap 0 --csv");
  ASSERT_EQ(csv.code, 0) << csv.err;
  EXPECT_NE(csv.out.find("m1,,auc_ds,0.5954217774044879"), std::string::npos) << csv.out;
  EXPECT_NE(csv.out.find("m1,m2,delong_auc_ds_p,"), std::string::npos) << csv.out;
}

// Metrics in separate files (--more-scores) give what one file of both columns gives; a name
// taken already gets its file's stem in front.
TEST_F(EvalCli, MoreScoresFilesAreComparedWithTheFirst) {
  std::string a = "stimulus,psnr\n", b = "stimulus,ssim\n", same = "stimulus,psnr\n";
  for (const auto& e : reference_rows("toyama_krasula_stimuli.csv")) {
    a += e.at("stimulus") + "," + e.at("psnr") + "\n";
    b += e.at("stimulus") + "," + e.at("ssim") + "\n";
    same += e.at("stimulus") + "," + e.at("ssim") + "\n";
  }
  const fs::path fa = file("a.csv", a), fb = file("b.csv", b), fs2 = file("run2.csv", same);
  const std::string table = (evaluation_dir() / "toyama_krasula_stimuli.csv").string();
  const std::string common = " --scores-key stimulus --mos-column MOS --sd-column SD "
                             "--n-column num_obs --bootstrap 0 --json";
  const CliRun one = qm3d("eval " + table + " " + table + " --scores-column psnr,ssim" + common);
  const CliRun two = qm3d("eval " + fa.string() + " " + table + " --more-scores " + fb.string() + common);
  ASSERT_EQ(one.code, 0) << one.err;
  ASSERT_EQ(two.code, 0) << two.err;
  const json j1 = json::parse(one.out), j2 = json::parse(two.out);
  EXPECT_EQ(j1["metrics"], j2["metrics"]);
  EXPECT_EQ(j1["comparisons"], j2["comparisons"]);
  const CliRun clash = qm3d("eval " + fa.string() + " " + table + " --more-scores " + fs2.string() + common);
  ASSERT_EQ(clash.code, 0) << clash.err;
  const json j3 = json::parse(clash.out);
  EXPECT_TRUE(j3["metrics"].contains("psnr"));
  EXPECT_TRUE(j3["metrics"].contains("run2:psnr"));
  EXPECT_EQ(j3["metrics"]["run2:psnr"]["krasula"], j1["metrics"]["ssim"]["krasula"]);
}

// VMAF's raw-score test from a long-format file of individual scores.
TEST_F(EvalCli, KrasulaFromIndividualScoresAsVmaf) {
  std::string scores = "stimulus,a,b\n", raw = "stimulus,observer,score\n", mos = "stimulus,mos\n";
  for (const auto& e : reference_rows("vmaf_rawscore_vector.csv")) {
    scores += e.at("stimulus") + "," + e.at("prediction_a") + "," + e.at("prediction_b") + "\n";
    double sum = 0;
    for (int k = 1; k <= 10; ++k) {
      raw += e.at("stimulus") + ",o" + std::to_string(k) + "," + e.at("score" + std::to_string(k)) + "\n";
      sum += std::stod(e.at("score" + std::to_string(k)));
    }
    mos += e.at("stimulus") + "," + exact(sum / 10) + "\n";
  }
  // Five stimuli are needed for the logistic fit: a fifth, far better one.
  scores += "5,5,5\n";
  mos += "5,9\n";
  for (int k = 1; k <= 10; ++k) raw += "5,o" + std::to_string(k) + "," + std::to_string(9 + 0.01 * k) + "\n";
  const fs::path s = file("scores.csv", scores), r = file("raw.csv", raw), m = file("mos.csv", mos);
  const CliRun run = qm3d("eval " + s.string() + " " + m.string() + " --scores-column a,b --raw " +
                          r.string() + " --bootstrap 0 --json");
  ASSERT_EQ(run.code, 0) << run.err;
  const json j = json::parse(run.out);
  EXPECT_EQ(j["krasula"]["pairs"], 25);  // every ordered pair, self-pairs included
  EXPECT_GT(j["metrics"]["a"]["krasula"]["auc_bw"].get<double>(),
            j["metrics"]["b"]["krasula"]["auc_bw"].get<double>());
  // Unknown stimuli in the raw file are an error naming the file and line.
  const fs::path bad = file("bad_raw.csv", raw + "9,o1,3\n");
  const CliRun unknown = qm3d("eval " + s.string() + " " + m.string() +
                              " --scores-column a,b --raw " + bad.string() + " --bootstrap 0");
  EXPECT_EQ(unknown.code, 2);
  EXPECT_NE(unknown.err.find(bad.string() + ":52: stimulus \"9\" is not among the evaluated"),
            std::string::npos)
      << unknown.err;
}

// Batch results of several metrics: one series per metric, oriented by the registry.
TEST_F(EvalCli, BatchFileOfSeveralMetricsIsOneColumnPerMetric) {
  std::string batch = "reference,distorted,metric,score,status\n";
  std::string mos = "distorted,mos,sd,n\n";
  const double q[] = {1.1, 1.9, 3.2, 3.8, 4.4, 4.9};
  for (int k = 0; k < 6; ++k) {
    const std::string d = "s" + std::to_string(k) + ".ply";
    batch += "r.ply," + d + ",pcqm," + exact(0.05 - 0.008 * k + 0.001 * (k % 2)) + ",ok\n";
    batch += "r.ply," + d + ",psnr," + exact(20 + 4 * k - 0.5 * (k % 3)) + ",ok\n";
    mos += d + "," + exact(q[k]) + ",0.6,20\n";
  }
  batch += "r.ply,s9.ply,compare,,error\n";  // a failed pair of `compare`: no metric column
  mos += "s9.ply,3,0.6,20\n";
  const fs::path b = file("results.csv", batch), m = file("mos.csv", mos);
  const CliRun run = qm3d("eval " + b.string() + " " + m.string() +
                          " --sd-column sd --n-column n --bootstrap 0 --json");
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_NE(run.err.find("compare has no finite score"), std::string::npos) << run.err;
  const json j = json::parse(run.out);
  EXPECT_EQ(j["metrics"]["pcqm"]["orientation"]["higher_is_better"], false);
  EXPECT_EQ(j["metrics"]["psnr"]["orientation"]["higher_is_better"], true);
  EXPECT_EQ(j["metrics"]["psnr"]["orientation"]["from"], "metric column: psnr");
  // Oriented, both order the different pairs rightly.
  EXPECT_EQ(j["metrics"]["pcqm"]["krasula"]["c0"], 1.0);
  EXPECT_EQ(j["metrics"]["psnr"]["krasula"]["c0"], 1.0);
  EXPECT_LT(j["metrics"]["pcqm"]["statistics"]["srocc"]["value"].get<double>(), 0);

  // Bad subjective data: an SD missing, n < 2, a bad label.
  std::string no_sd = mos;
  no_sd.replace(no_sd.find(",0.6,20\n"), 8, ",,20\n");
  const fs::path m1 = file("no_sd.csv", no_sd);
  const CliRun missing = qm3d("eval " + b.string() + " " + m1.string() +
                              " --sd-column sd --n-column n --bootstrap 0");
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.err.find(m1.string() + ":2: column \"sd\": no standard deviation"),
            std::string::npos)
      << missing.err;
  std::string one = mos;
  one.replace(one.find(",0.6,20\n"), 8, ",0.6,1\n");
  const fs::path m2 = file("one.csv", one);
  const CliRun few = qm3d("eval " + b.string() + " " + m2.string() +
                          " --sd-column sd --n-column n --bootstrap 0");
  EXPECT_EQ(few.code, 2);
  EXPECT_NE(few.err.find(m2.string() + ":2: 1.000000 observers"), std::string::npos) << few.err;
  const fs::path p = file("p.csv", "first,second,label\ns1.ply,s0.ply,2\n");
  const CliRun label = qm3d("eval " + b.string() + " " + m.string() + " --pairs " + p.string() +
                            " --bootstrap 0");
  EXPECT_EQ(label.code, 2);
  EXPECT_NE(label.err.find(p.string() + ":2: the label must be 1"), std::string::npos) << label.err;
}

// --mapping linear: the P.1401 values follow from the least-squares line, recomputed here; with
// CIs, RMSE* and the outlier ratio and their tests between the two metrics.
TEST_F(EvalCli, P1401StatisticsAfterTheChosenMapping) {
  const std::vector<double> mos = {1.2, 1.9, 2.7, 3.1, 3.9, 4.4, 4.8, 2.2};
  const std::vector<double> ci = {0.2, 0.3, 0.2, 0.25, 0.3, 0.2, 0.15, 0.3};
  const std::vector<double> a = {0.9, 2.1, 2.5, 3.4, 3.7, 4.6, 4.7, 2.0};
  const std::vector<double> b = {10, 22, 24, 37, 35, 41, 50, 26};
  std::string scores = "distorted,a,b\n", subjective = "distorted,mos,ci\n";
  for (std::size_t i = 0; i < mos.size(); ++i) {
    scores += "s" + std::to_string(i) + "," + exact(a[i]) + "," + exact(b[i]) + "\n";
    subjective += "s" + std::to_string(i) + "," + exact(mos[i]) + "," + exact(ci[i]) + "\n";
  }
  const fs::path s = file("scores.csv", scores), m = file("mos.csv", subjective);
  const CliRun run = qm3d("eval " + s.string() + " " + m.string() +
                          " --scores-column a,b --ci-column ci --mapping linear --bootstrap 0 --json");
  ASSERT_EQ(run.code, 0) << run.err;
  const json j = json::parse(run.out);
  // The line y = p x + q by least squares, and RMSE with N - 2 degrees of freedom.
  const double n = static_cast<double>(mos.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < mos.size(); ++i) {
    sx += a[i], sy += mos[i], sxx += a[i] * a[i], sxy += a[i] * mos[i];
  }
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx), icept = (sy - slope * sx) / n;
  double sse = 0, star = 0;
  std::size_t outliers = 0;
  for (std::size_t i = 0; i < mos.size(); ++i) {
    const double e = std::fabs(mos[i] - (slope * a[i] + icept));
    sse += e * e;
    star += std::pow(std::max(0.0, e - ci[i]), 2);
    outliers += e > ci[i];
  }
  const json& st = j["metrics"]["a"]["statistics"];
  EXPECT_EQ(j["metrics"]["a"]["mapping"]["name"], "linear");
  EXPECT_EQ(j["metrics"]["a"]["mapping"]["degrees_of_freedom"], 6);
  EXPECT_NEAR(st["rmse_mapped"]["value"].get<double>(), std::sqrt(sse / (n - 2)), 1e-12);
  EXPECT_NEAR(st["rmse_star"]["value"].get<double>(), std::sqrt(star / (n - 2)), 1e-12);
  EXPECT_NEAR(st["outlier_ratio"]["value"].get<double>(), static_cast<double>(outliers) / n, 1e-15);
  EXPECT_TRUE(st["rmse_mapped"]["ci95"].is_array());
  std::set<std::string> tests;
  for (const json& c : j["comparisons"]) tests.insert(c["test"].get<std::string>());
  EXPECT_EQ(tests, (std::set<std::string>{"fisher_z_plcc", "f_rmse", "f_rmse_star", "outlier_ratio"}));
  EXPECT_TRUE(j["krasula"].is_null());
}

TEST_F(EvalCli, BadInputIsOneLineNamingTheFileAndColumn) {
  const auto one_line_error = [](const CliRun& r) {
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(r.err.find("qm3d: error: "), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  };
  const std::string s = basics_scores(), m = basics_mos();
  CliRun r = qm3d("eval " + s + " " + m + " --mos-column quality");
  one_line_error(r);
  EXPECT_NE(
      r.err.find("basics_mos.csv: no column \"quality\" (columns: stimulus, mos); set it with "
                 "--mos-column"),
      std::string::npos)
      << r.err;
  const fs::path bad = file("bad.csv", "stimulus,mos\np01_geocnn_r01,4.5\np01_geocnn_r02,good\n");
  r = qm3d("eval " + s + " " + bad.string());
  one_line_error(r);
  EXPECT_NE(r.err.find("bad.csv:3: column \"mos\": \"good\" is not a number"), std::string::npos)
      << r.err;
  const fs::path other = file("other.csv", "stimulus,mos\nx,1\ny,2\n");
  r = qm3d("eval " + s + " " + other.string());
  one_line_error(r);
  EXPECT_NE(r.err.find("no stimulus in common between"), std::string::npos) << r.err;
  const fs::path three = file("three.csv", "a,b,c\nx,1,2\n");
  r = qm3d("eval " + three.string() + " " + m);
  one_line_error(r);
  EXPECT_NE(r.err.find("three.csv: which column holds the values? set it with --scores-column"),
            std::string::npos)
      << r.err;
  const fs::path twice = file("twice.csv", "stimulus,mos\nx,1\nx,2\n");
  r = qm3d("eval " + s + " " + twice.string());
  one_line_error(r);
  EXPECT_NE(r.err.find("twice.csv:3: key \"x\" already on line 2"), std::string::npos) << r.err;
  r = qm3d("eval /nonexistent/scores.csv " + m);
  one_line_error(r);
  EXPECT_NE(r.err.find("/nonexistent/scores.csv: no such file"), std::string::npos) << r.err;
}

TEST_F(EvalCli, SvgAndPngPlotsFromOneDescription) {
  const fs::path svg = dir_ / "io" / "plot.svg";
  const std::string args = "eval " + basics_scores() + " " + basics_mos() + " --bootstrap 0 -q";
  ASSERT_EQ(qm3d(args + " --plot " + svg.string()).code, 0);
  const std::string text = slurp(svg);
  EXPECT_EQ(text.rfind("<?xml", 0), 0u);
  EXPECT_NE(text.find("<polyline"), std::string::npos);
  std::size_t circles = 0;
  for (auto p = text.find("<circle"); p != std::string::npos; p = text.find("<circle", p + 1))
    ++circles;
  EXPECT_EQ(circles, 1140u);
  // PNG: drawn by qm3d itself (no gnuplot on the PATH needed), the same size as the SVG.
  const fs::path png = dir_ / "io" / "plot.png";
  const CliRun drawn = qm3d(args + " --plot " + png.string(), "PATH=/nonexistent");
  ASSERT_EQ(drawn.code, 0) << drawn.err;
  int w = 0, h = 0, channels = 0;
  ASSERT_TRUE(stbi_info(png.c_str(), &w, &h, &channels));
  EXPECT_EQ(w, 720);
  EXPECT_EQ(h, 540);
  EXPECT_EQ(qm3d(args + " --plot " + (dir_ / "io" / "plot.gif").string()).code, 2);
}

// The numbers of attribute `name` in an SVG element.
double svg_attribute(const std::string& element, const std::string& name) {
  const std::string key = " " + name + "=\"";
  const std::size_t at = element.find(key);
  return at == std::string::npos ? NAN : std::stod(element.substr(at + key.size()));
}

// Krasula's AUC figure as SVG and PNG: with AUCs far below chance (a column ranking the stimuli
// the wrong way round), every bar stands inside the axes, and the PNG shows each one.
TEST_F(EvalCli, AucFigureShowsEveryBarInSvgAndPng) {
  std::string scores = "stimulus,right,wrong\n", mos = "stimulus,mos,sd,n\n";
  for (int k = 0; k < 24; ++k) {
    const double q = 1 + 4.0 * k / 23 + 0.3 * std::sin(k);
    scores += "s" + std::to_string(k) + "," + exact(q + 0.2 * std::cos(3 * k)) + "," +
              exact(-q + 1.6 * std::cos(5 * k)) + "\n";
    mos += "s" + std::to_string(k) + "," + exact(q) + ",0.8,20\n";
  }
  const fs::path s = file("scores.csv", scores), m = file("mos.csv", mos);
  const std::string args = "eval " + s.string() + " " + m.string() +
                           " --scores-column right,wrong --sd-column sd --n-column n "
                           "--bootstrap 0 -q --json --plot ";
  const CliRun run = qm3d(args + (dir_ / "io" / "fig.svg").string());
  ASSERT_EQ(run.code, 0) << run.err;
  const json j = json::parse(run.out);
  EXPECT_LT(j["metrics"]["wrong"]["krasula"]["auc_bw"].get<double>(), 0.1);  // 0.078
  ASSERT_EQ(qm3d(args + (dir_ / "io" / "fig.png").string()).code, 0);
  const std::string svg = slurp(dir_ / "io" / "fig-auc.svg");
  ASSERT_FALSE(svg.empty());
  // The frame: the first outlined rectangle; the bars: the translucent ones.
  const std::size_t frame_at = svg.find("stroke=\"black\"/>");
  const std::size_t frame_start = svg.rfind("<rect", frame_at);
  const std::string frame = svg.substr(frame_start, frame_at - frame_start);
  const double top = svg_attribute(frame, "y"), bottom = top + svg_attribute(frame, "height");
  int w = 0, h = 0, channels = 0;
  unsigned char* png = stbi_load((dir_ / "io" / "fig-auc.png").c_str(), &w, &h, &channels, 3);
  ASSERT_NE(png, nullptr);
  std::size_t bars = 0;
  for (auto p = svg.find("<rect"); p != std::string::npos; p = svg.find("<rect", p + 1)) {
    const std::string bar = svg.substr(p, svg.find('>', p) - p);
    if (bar.find("fill-opacity=\"0.70\"") == std::string::npos) continue;
    ++bars;
    const double x = svg_attribute(bar, "x"), y = svg_attribute(bar, "y");
    const double bw = svg_attribute(bar, "width"), bh = svg_attribute(bar, "height");
    EXPECT_GE(y, top) << bar;
    EXPECT_LE(y + bh, bottom + 0.01) << bar;
    EXPECT_GE(bh, 4.0) << bar;  // visible
    // The PNG pixel a quarter into the bar (off its whisker) has the bar's colour over white.
    const std::size_t px = static_cast<std::size_t>(x + bw / 4),
                      py = static_cast<std::size_t>(y + bh / 2);
    const unsigned char* rgb = png + (py * static_cast<std::size_t>(w) + px) * 3;
    const std::string hex = bar.substr(bar.find("fill=\"#") + 7, 6);
    for (int c = 0; c < 3; ++c) {
      const double colour = std::stoi(hex.substr(2 * c, 2), nullptr, 16);
      EXPECT_NEAR(rgb[c], 0.7 * colour + 0.3 * 255, 2) << bar << " channel " << c;
    }
  }
  stbi_image_free(png);
  EXPECT_EQ(bars, 4u);  // AUC_DS and AUC_BW of two metrics
}

// ---- train ---------------------------------------------------------------------------------

// Features uniform in [0, 1) (f3 of a larger scale), MOS = decreasing logistic of `weights`.f
// plus N(0, noise_sd); `groups` source models of `per_group` stimuli.
struct SyntheticFiles {
  std::string features, mos;
};

SyntheticFiles synthetic_csv(const FeatureVector& weights, const LogisticFunction& mapping,
                             int groups, int per_group, double noise_sd, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::ostringstream features, mos;
  features << "stimulus,source,f1,f2,f3,f4,f5,f6,f7,f8\n";
  mos << "stimulus,mos\n";
  for (int g = 0; g < groups; ++g) {
    for (int i = 0; i < per_group; ++i) {
      const std::string key = "m" + std::to_string(g) + "_d" + std::to_string(i);
      features << key << ",model" << g;
      double score = 0;
      for (std::size_t k = 0; k < kNumFeatures; ++k) {
        const double f = uniform01(rng) * (k == 2 ? 10 : 1);
        features << "," << exact(f);
        score += weights[k] * f;
      }
      features << "\n";
      mos << key << "," << exact(mapping(score) + noise_sd * normal(rng)) << "\n";
    }
  }
  return {features.str(), mos.str()};
}

TEST_F(EvalCli, TrainFindsTheTrueSubsetAndWritesAModel) {
  const FeatureVector truth = {0, 0.2, 0, 0, 0.3, 0, 0.5, 0};
  const SyntheticFiles data = synthetic_csv(truth, {1, 5, 0.5, 0.08}, 6, 40, 0.1, 1);
  const fs::path features = file("features.csv", data.features), mos = file("mos.csv", data.mos);
  const fs::path model = dir_ / "io" / "model.json", report = dir_ / "io" / "subsets.csv";
  const CliRun r = qm3d("train " + features.string() + " " + mos.string() +
                        " --group-by source --metric pcqm -o " + model.string() + " --report " +
                        report.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("240 stimuli, features f of pcqm, 6 folds (source), 255 subsets"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("f2,f5,f7"), std::string::npos) << r.out;
  const json m = json::parse(slurp(model));
  EXPECT_EQ(m["format"], "qm3d-model/1");
  EXPECT_EQ(m["metric"], "pcqm");
  ASSERT_EQ(m["features"], json::array({"f2", "f5", "f7"}));
  // Stated tolerance: every weight within 0.01 of the truth.
  EXPECT_NEAR(m["weights"][0].get<double>(), 0.2, 0.01);
  EXPECT_NEAR(m["weights"][1].get<double>(), 0.3, 0.01);
  EXPECT_NEAR(m["weights"][2].get<double>(), 0.5, 0.01);
  EXPECT_NE(m["provenance"].get<std::string>().find("leave-one-group-out"), std::string::npos);
  EXPECT_TRUE(m.contains("logistic"));
  const std::string rows = slurp(report);
  EXPECT_EQ(std::count(rows.begin(), rows.end(), '\n'), 256);
  EXPECT_EQ(
      rows.rfind("rank,subset,features,plcc_mean,plcc_sd,srocc_mean,srocc_sd,chosen,error\n", 0),
      0u);
  EXPECT_NE(rows.find(",\"f2,f5,f7\",3,"), std::string::npos) << rows.substr(0, 400);
}

TEST_F(EvalCli, TrainedBuiltInWeightsReproduceTheBuiltInScore) {
  // Noise-free data generated with PCQM's own weights: training on f3,f4,f6 gives them back,
  // and `qm3d pcqm --model` then scores as the built-in model does.
  const SyntheticFiles data = synthetic_csv(pcqm_model().weights, {1, 5, 0.5, 0.1}, 4, 20, 0, 2);
  const fs::path features = file("features.csv", data.features), mos = file("mos.csv", data.mos);
  const fs::path model = dir_ / "io" / "model.json";
  const CliRun t = qm3d("train " + features.string() + " " + mos.string() +
                        " --group-by source --metric pcqm --subset f3,f4,f6 --final refit -q -o " +
                        model.string());
  ASSERT_EQ(t.code, 0) << t.err;
  const json m = json::parse(slurp(model));
  ASSERT_EQ(m["features"], json::array({"f3", "f4", "f6"}));
  EXPECT_NEAR(m["weights"][0].get<double>(), 0.0057, 1e-7);
  EXPECT_NEAR(m["weights"][1].get<double>(), 0.9771, 1e-7);
  EXPECT_NEAR(m["weights"][2].get<double>(), 0.0172, 1e-7);
  const std::string pair =
      (test::source_dir() / "data" / "clouds" / "sphere_2k_ref.ply").string() + " " +
      (test::source_dir() / "data" / "clouds" / "sphere_2k_cnoise10.ply").string();
  const CliRun builtin = qm3d("pcqm " + pair + " --json -q");
  const CliRun trained = qm3d("pcqm " + pair + " --model " + model.string() + " --json -q");
  const CliRun file_model = qm3d("pcqm " + pair + " --json -q --model " +
                                 (test::source_dir() / "data" / "models" / "pcqm.json").string());
  ASSERT_EQ(builtin.code, 0) << builtin.err;
  ASSERT_EQ(trained.code, 0) << trained.err;
  ASSERT_EQ(file_model.code, 0) << file_model.err;
  const double expected = json::parse(builtin.out)["score"].get<double>();
  EXPECT_GT(expected, 0.0);
  EXPECT_NEAR(json::parse(trained.out)["score"].get<double>(), expected, 1e-6 * expected);
  // The built-in model file gives the built-in score exactly.
  EXPECT_EQ(json::parse(file_model.out)["score"].get<double>(), expected);
}

TEST_F(EvalCli, CmdmModelFileAndMetricMismatch) {
  const std::string pair = (test::source_dir() / "data" / "meshes" / "blob3_ref.off").string() +
                           " " +
                           (test::source_dir() / "data" / "meshes" / "blob3_colnoise.off").string();
  const std::string models = (test::source_dir() / "data" / "models").string();
  const CliRun builtin = qm3d("cmdm " + pair + " --json -q");
  const CliRun file_model = qm3d("cmdm " + pair + " --json -q --model " + models + "/cmdm.json");
  ASSERT_EQ(builtin.code, 0) << builtin.err;
  ASSERT_EQ(file_model.code, 0) << file_model.err;
  EXPECT_EQ(json::parse(file_model.out)["score"], json::parse(builtin.out)["score"]);
  const CliRun wrong = qm3d("cmdm " + pair + " --model " + models + "/pcqm.json");
  EXPECT_EQ(wrong.code, 2);
  EXPECT_NE(wrong.err.find("pcqm.json: model file: it is a \"pcqm\" model, not a \"cmdm\" one"),
            std::string::npos)
      << wrong.err;
  EXPECT_EQ(
      qm3d("cmdm " + pair + " --model " + models + "/cmdm.json --weights 1,0,0,0,0,0,0,0").code,
      1);  // usage error: one or the other
}

TEST_F(EvalCli, TrainReadsBatchResultsAndReportsItsErrors) {
  // Batch-style results (both directions, metric column, paths) against names: --stem, the
  // features of both directions averaged, the metric taken from the file.
  const SyntheticFiles data =
      synthetic_csv({0, 0, 0, 1, 0, 0, 0, 0}, {1, 5, 0.5, 0.1}, 3, 10, 0.05, 3);
  std::istringstream in(data.features);
  std::string line;
  std::getline(in, line);
  std::ostringstream batch;
  batch << "reference,distorted,metric,score,status,error,seconds";
  for (const char* d : {"dist_to_ref", "ref_to_dist"}) {
    batch << "," << d << "_score," << d << "_bbox_max_side";
    for (int k = 1; k <= 8; ++k) batch << "," << d << "_f" << k;
  }
  batch << "\n";
  while (std::getline(in, line)) {
    const std::string key = line.substr(0, line.find(','));
    const std::string f = line.substr(line.find(',', line.find(',') + 1));  // ",f1,...,f8"
    batch << "/refs/r.ply,/dist/" << key << ".ply,cmdm,0.1,ok,,1,0.1,1" << f << ",0.1,1" << f
          << "\n";
  }
  const fs::path features = file("results.csv", batch.str());
  const fs::path mos = file("mos.csv", data.mos + "extra,3\n");
  const fs::path model = dir_ / "io" / "model.json";
  const std::string args = "train " + features.string() + " " + mos.string();
  const CliRun r = qm3d(args + " --group-by source --stem --subset f4 --subset f4,f5 --json -o " +
                        model.string());
  EXPECT_EQ(r.code, 2);  // "source" is in neither file
  EXPECT_NE(r.err.find("--group-by: no column \"source\" in"), std::string::npos) << r.err;
  const fs::path mos_groups = file(
      "mos_groups.csv", "stimulus,mos,model\n" + [&] {
        std::string out;
        std::istringstream m(data.mos);
        std::getline(m, line);
        while (std::getline(m, line)) out += line + "," + line.substr(0, 2) + "\n";
        return out;
      }());
  const CliRun ok =
      qm3d("train " + features.string() + " " + mos_groups.string() +
           " --group-by model --stem --subset f4 --subset f4,f5 --json -o " + model.string());
  ASSERT_EQ(ok.code, 0) << ok.err;
  const json j = json::parse(ok.out);
  EXPECT_EQ(j["features"]["prefixes"], json::array({"dist_to_ref_f", "ref_to_dist_f"}));
  EXPECT_EQ(j["stimuli"], 30);
  EXPECT_EQ(j["folds"].size(), 3u);
  EXPECT_EQ(j["chosen"]["subset"], "f4");
  EXPECT_EQ(j["subsets"].size(), 2u);
  EXPECT_EQ(json::parse(slurp(model))["metric"], "cmdm");
  const CliRun bad_prefix = qm3d("train " + features.string() + " " + mos_groups.string() +
                                 " --group-by model --stem --features mos");
  EXPECT_EQ(bad_prefix.code, 2);
  EXPECT_NE(bad_prefix.err.find("results.csv: no column \"mos1\""), std::string::npos)
      << bad_prefix.err;
  const fs::path plain = file("plain.csv", data.features);
  const CliRun no_metric =
      qm3d("train " + plain.string() + " " + mos_groups.string() + " --group-by model --subset f4");
  EXPECT_EQ(no_metric.code, 2);
  EXPECT_NE(no_metric.err.find("plain.csv: no \"metric\" column; say which metric the model is "
                               "for with --metric cmdm|pcqm"),
            std::string::npos)
      << no_metric.err;
}

}  // namespace
}  // namespace qm3d
