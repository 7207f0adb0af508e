// Krasula's analysis against ../shared/data/reference/evaluation/ (README there): the Toyama
// vectors of Netflix/vmaf and krasuluk/AucPerformance, the values VMAF's unit test asserts, and
// every per-metric and pairwise value VMAF's and Krasula's code give on them.
#include "qm3d/evaluation/krasula.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "qm3d/evaluation/evaluation.h"
#include "test_paths.h"

namespace qm3d {
namespace {
using namespace qm3d::evaluation;  // the toolkit under test (qm3d/evaluation/)

// A CSV of the reference folder as rows of named cells (a quoted field may hold commas).
using Row = std::map<std::string, std::string>;

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> cells(1);
  bool quoted = false;
  for (char c : line) {
    if (c == '"') quoted = !quoted;
    else if (c == ',' && !quoted) cells.emplace_back();
    else cells.back() += c;
  }
  return cells;
}

std::vector<Row> read_csv(const std::string& name) {
  const auto path = test::reference_dir() / "evaluation" / name;
  std::ifstream in(path);
  EXPECT_TRUE(in) << path;
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = split(line);
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    const std::vector<std::string> cells = split(line);
    EXPECT_EQ(cells.size(), header.size()) << path << ": " << line;
    Row r;
    for (std::size_t c = 0; c < header.size() && c < cells.size(); ++c) r[header[c]] = cells[c];
    rows.push_back(r);
  }
  return rows;
}

double num(const Row& r, const std::string& column) { return std::stod(r.at(column)); }

void expect_rel(double got, double expected, double tol, const std::string& what) {
  EXPECT_NEAR(got, expected, tol * std::fabs(expected)) << what;
}

// The VMAF vector: 5 metrics' differences on 14028 labelled pairs.
struct VmafVector {
  std::vector<std::vector<double>> differences = std::vector<std::vector<double>>(5);
  std::vector<int> labels;
  std::vector<std::size_t> first, second;
};

const VmafVector& vmaf_vector() {
  static const VmafVector v = [] {
    VmafVector out;
    for (const Row& r : read_csv("toyama_vmaf_pairs.csv")) {
      out.labels.push_back(std::stoi(r.at("signif")));
      out.first.push_back(std::stoul(r.at("first")) - 1);
      out.second.push_back(std::stoul(r.at("second")) - 1);
      for (int m = 0; m < 5; ++m) out.differences[m].push_back(num(r, "d" + std::to_string(m + 1)));
    }
    return out;
  }();
  return v;
}

void expect_vmaf_per_metric_and_pairwise(const KrasulaResult& r) {
  EXPECT_EQ(r.different, 11121u);
  EXPECT_EQ(r.similar, 2907u);
  const std::vector<Row> per_metric = read_csv("toyama_vmaf_computed_per_metric.csv");
  ASSERT_EQ(per_metric.size(), 5u);
  ASSERT_EQ(r.metrics.size(), 5u);
  for (std::size_t m = 0; m < 5; ++m) {
    const Row& e = per_metric[m];
    const KrasulaMetric& k = r.metrics[m];
    const std::string id = "metric " + std::to_string(m + 1);
    expect_rel(k.auc_ds, num(e, "AUC_DS"), 1e-12, id + " AUC_DS");
    expect_rel(k.auc_bw, num(e, "AUC_BW"), 1e-12, id + " AUC_BW");
    expect_rel(k.c0, num(e, "CC_0"), 1e-12, id + " CC_0");
    expect_rel(k.thr_numpy, num(e, "THR_numpy"), 1e-12, id + " THR_numpy");
    expect_rel(k.thr_prctile, num(e, "THR_prctile"), 1e-12, id + " THR_prctile");
    expect_rel(k.se_ds, num(e, "SE_DS_DeLong"), 1e-12, id + " SE_DS");
    expect_rel(k.se_bw, num(e, "SE_BW_DeLong"), 1e-12, id + " SE_BW");
  }
  const std::vector<Row> pairwise = read_csv("toyama_vmaf_computed_pairwise.csv");
  std::size_t compared = 0;
  for (const Row& e : pairwise) {
    const std::size_t a = std::stoul(e.at("metric_a")) - 1, b = std::stoul(e.at("metric_b")) - 1;
    const std::string id = std::to_string(a + 1) + "-" + std::to_string(b + 1);
    expect_rel(r.cov_ds[a * 5 + b], num(e, "cov_DS"), 1e-12, id + " cov_DS");
    expect_rel(r.cov_bw[a * 5 + b], num(e, "cov_BW"), 1e-12, id + " cov_BW");
    if (a == b) continue;
    const KrasulaComparison* c = nullptr;
    for (const KrasulaComparison& x : r.comparisons) {
      if (x.a == a && x.b == b) c = &x;
    }
    ASSERT_NE(c, nullptr) << id;
    EXPECT_NEAR(c->p_delong_ds, num(e, "pDS_DL"), 1e-9) << id;
    EXPECT_NEAR(c->p_delong_bw, num(e, "pBW_DL"), 1e-9) << id;
    EXPECT_NEAR(c->p_c0, num(e, "pCC0_b"), 1e-9) << id;
    ++compared;
  }
  EXPECT_EQ(compared, 10u);
}

TEST(Krasula, VmafVectorEveryPerMetricAndPairwiseValue) {
  const VmafVector& v = vmaf_vector();
  expect_vmaf_per_metric_and_pairwise(krasula_analysis(v.differences, v.labels));
}

// VMAF's test_auc_metrics_performance: the means over the 5 metrics, to the 6 places it
// asserts and to 1e-12 of the 17-digit value.
TEST(Krasula, VmafUnitTestMeans) {
  const VmafVector& v = vmaf_vector();
  const KrasulaResult r = krasula_analysis(v.differences, v.labels);
  double ds = 0, bw = 0, c0 = 0, thr = 0;
  for (const KrasulaMetric& m : r.metrics) ds += m.auc_ds, bw += m.auc_bw, c0 += m.c0, thr += m.thr_numpy;
  const std::map<std::string, double> got = {
      {"mean(AUC_DS)", ds / 5}, {"mean(AUC_BW)", bw / 5}, {"mean(CC_0)", c0 / 5}, {"mean(THR)", thr / 5}};
  std::size_t checked = 0;
  for (const Row& e : read_csv("vmaf_perf_metric_test_expected.csv")) {
    if (e.at("test") != "test_auc_metrics_performance") continue;
    const double value = got.at(e.at("quantity"));
    EXPECT_EQ(std::round((value - num(e, "expected_as_written")) * 1e6), 0.0) << e.at("quantity");
    expect_rel(value, num(e, "computed"), 1e-12, e.at("quantity"));
    ++checked;
  }
  EXPECT_EQ(checked, 4u);
}

// The same vector rebuilt from the per-stimulus table: qm3d's J.149 labels are VMAF's signif on
// every pair, the differences its d1..d5 bit for bit, so every value follows.
TEST(Krasula, LabelsFromMosSdAndNAreTheVmafVectors) {
  std::vector<double> mos, sd, n;
  std::vector<std::vector<double>> scores(5);
  for (const Row& r : read_csv("toyama_stimuli_5metrics.csv")) {
    mos.push_back(num(r, "MOS"));
    sd.push_back(num(r, "SD"));
    n.push_back(num(r, "n"));
    for (int m = 0; m < 5; ++m) scores[m].push_back(num(r, "m" + std::to_string(m + 1)));
  }
  const PairLabels pairs = label_pairs_j149(mos, sd, n);
  const VmafVector& v = vmaf_vector();
  ASSERT_EQ(pairs.size(), v.labels.size());
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    ASSERT_EQ(pairs.first(p), v.first[p]) << "pair " << p + 1;
    ASSERT_EQ(pairs.second(p), v.second[p]) << "pair " << p + 1;
    ASSERT_EQ(pairs.label[p], v.labels[p]) << "pair " << p + 1;
  }
  expect_vmaf_per_metric_and_pairwise(krasula_analysis(scores, pairs));
}

// Krasula's own example (PSNR vs SSIM on Example_Toyama.mat) from the stimulus table alone.
TEST(Krasula, KrasulasExampleFromTheStimulusTable) {
  std::vector<double> mos, sd, n;
  std::vector<std::vector<double>> scores(2);
  for (const Row& r : read_csv("toyama_krasula_stimuli.csv")) {
    mos.push_back(num(r, "MOS"));
    sd.push_back(num(r, "SD"));
    n.push_back(num(r, "num_obs"));
    scores[0].push_back(num(r, "psnr"));
    scores[1].push_back(num(r, "ssim"));
  }
  const PairLabels pairs = label_pairs_j149(mos, sd, n);
  const KrasulaResult r = krasula_analysis(scores, pairs);
  std::size_t checked = 0;
  for (const Row& e : read_csv("toyama_krasula_octave_expected.csv")) {
    const std::string q = e.at("quantity"), metric = e.at("metric");
    const double expected = num(e, "value");
    const std::size_t m = metric == "ssim" ? 1 : 0;
    // Krasula counts over his (i, j), i < j, orientation: his +1 are our -1.
    if (q == "n_plus") EXPECT_EQ(r.different - r.better, expected);
    else if (q == "n_minus") EXPECT_EQ(r.better, expected);
    else if (q == "n_zero") EXPECT_EQ(r.similar, expected);
    else if (q == "AUC_DS") expect_rel(r.metrics[m].auc_ds, expected, 1e-12, q + " " + metric);
    else if (q == "AUC_BW") expect_rel(r.metrics[m].auc_bw, expected, 1e-12, q + " " + metric);
    else if (q == "CC_0") expect_rel(r.metrics[m].c0, expected, 1e-12, q + " " + metric);
    else if (q == "THR") expect_rel(r.metrics[m].thr_prctile, expected, 1e-12, q + " " + metric);
    else if (q == "SROCC") expect_rel(spearman(scores[m], mos), expected, 1e-12, q + " " + metric);
    else if (q == "KROCC") expect_rel(kendall_tau_b(scores[m], mos), expected, 1e-12, q + " " + metric);
    else if (q == "pDS_DL") EXPECT_NEAR(r.comparisons[0].p_delong_ds, expected, 1e-9);
    else if (q == "pBW_DL") EXPECT_NEAR(r.comparisons[0].p_delong_bw, expected, 1e-9);
    else if (q == "pCC0_b") EXPECT_NEAR(r.comparisons[0].p_c0, expected, 1e-9);
    else continue;  // Hanley-McNeil and Fisher exact p: not computed
    ++checked;
  }
  EXPECT_EQ(checked, 18u);
}

// VMAF's raw-score tests: every ordered pair of 4 stimuli with 10 scores each, self-pairs too.
TEST(Krasula, VmafRawScoreTests) {
  std::vector<std::vector<double>> raw;
  std::vector<std::vector<double>> predictions(2);
  for (const Row& r : read_csv("vmaf_rawscore_vector.csv")) {
    std::vector<double> s;
    for (int k = 1; k <= 10; ++k) s.push_back(num(r, "score" + std::to_string(k)));
    raw.push_back(s);
    predictions[0].push_back(num(r, "prediction_a"));
    predictions[1].push_back(num(r, "prediction_b"));
  }
  const PairLabels pairs = label_pairs_raw(raw);
  ASSERT_EQ(pairs.size(), 16u);
  const KrasulaResult r = krasula_analysis(predictions, pairs);
  std::size_t checked = 0;
  for (const Row& e : read_csv("vmaf_perf_metric_test_expected.csv")) {
    if (e.at("test") != "test_auc_perf_multiple_metrics") continue;
    const std::string q = e.at("quantity"), who = e.at("prediction");
    const KrasulaMetric& m = r.metrics[who == "b" ? 1 : 0];
    double got = 0;
    if (q == "score" || q == "AUC_BW") got = m.auc_bw;
    else if (q == "AUC_DS") got = m.auc_ds;
    else if (q == "CC_0") got = m.c0;
    else if (q == "THR") got = m.thr_numpy;
    else if (q == "pDS_DL") got = r.comparisons[0].p_delong_ds;
    else if (q == "pBW_DL") got = r.comparisons[0].p_delong_bw;
    else if (q == "pCC0_b") got = r.comparisons[0].p_c0;
    EXPECT_EQ(std::round((got - num(e, "expected_as_written")) * 1e6), 0.0) << q << " " << who;
    EXPECT_NEAR(got, num(e, "computed"), 1e-12 * std::max(1.0, std::fabs(num(e, "computed"))))
        << q << " " << who;
    ++checked;
  }
  EXPECT_EQ(checked, 13u);
}

TEST(Krasula, GroupsKeepPairsWithinASource) {
  const std::vector<double> mos = {1, 2, 3, 4}, sd = {0.1, 0.1, 0.1, 0.1}, n = {10, 10, 10, 10};
  const PairLabels all = label_pairs_j149(mos, sd, n);
  EXPECT_EQ(all.size(), 6u);
  const PairLabels within = label_pairs_j149(mos, sd, n, {"a", "b", "a", "b"});
  ASSERT_EQ(within.size(), 2u);
  EXPECT_EQ(within.first(0), 2u);
  EXPECT_EQ(within.second(0), 0u);
  EXPECT_EQ(within.label[0], 1);
}

TEST(Krasula, BadInputIsRefused) {
  EXPECT_THROW(label_pairs_j149({1, 2}, {0.1}, {10, 10}), std::invalid_argument);
  EXPECT_THROW(label_pairs_j149({1, 2}, {0.1, 0.1}, {10, 1}), std::invalid_argument);
  EXPECT_THROW(label_pairs_j149({1, NAN}, {0.1, 0.1}, {10, 10}), std::invalid_argument);
  EXPECT_THROW(label_pairs_j149({1, 2}, {-0.1, 0.1}, {10, 10}), std::invalid_argument);
  EXPECT_THROW(label_pairs_raw({{1, 2}, {3}}), std::invalid_argument);
  EXPECT_THROW(krasula_analysis(std::vector<std::vector<double>>{{1, 2}}, std::vector<int>{1}),
               std::invalid_argument);
  EXPECT_THROW(krasula_analysis(std::vector<std::vector<double>>{{1, 2}}, std::vector<int>{1, 2}),
               std::invalid_argument);
  EXPECT_THROW(krasula_analysis(std::vector<std::vector<double>>{{1, 2}}, std::vector<int>{1, 0}),
               std::invalid_argument);  // one different pair
  // Two different pairs and no similar one: AUC_BW and C0, the DS values NaN.
  const KrasulaResult r =
      krasula_analysis(std::vector<std::vector<double>>{{1, -2}}, std::vector<int>{1, -1});
  EXPECT_EQ(r.metrics[0].auc_bw, 1.0);
  EXPECT_EQ(r.metrics[0].c0, 1.0);
  EXPECT_TRUE(std::isnan(r.metrics[0].auc_ds));
}

}  // namespace
}  // namespace qm3d
