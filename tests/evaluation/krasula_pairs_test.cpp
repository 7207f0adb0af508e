// Krasula's analysis without pair lists (issue 37, item 4): the sorted formulation gives every
// value of the pair-list one (Mann-Whitney ranks and fastDeLong's structural components over
// listed pairs, as qm3d computed them up to 7db6918) on random data with ties, groups, both
// label rules and several metrics: the AUCs, C0 and THR bit for bit, the DeLong covariances
// (exact integer sums now, compensated double sums in pair order then) within 1e-12 relative
// (the off-diagonal ones relative to the geometric mean of their diagonal); the generated pairs
// are the ones listed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "qm3d/evaluation/evaluation.h"
#include "qm3d/evaluation/krasula.h"
#include "qm3d/evaluation/p1401.h"

namespace qm3d {
namespace {
using namespace qm3d::evaluation;  // the toolkit under test (qm3d/evaluation/)

// ---- the pair-list formulation, as it was (the oracle) ----------------------------------------

class Sum {
 public:
  void add(double x) {
    const double t = s_ + x;
    c_ += std::fabs(s_) >= std::fabs(x) ? (s_ - t) + x : (x - t) + s_;
    s_ = t;
  }
  double value() const { return s_ + c_; }

 private:
  double s_ = 0, c_ = 0;
};

struct DeLong {
  std::vector<double> aucs, cov;
};

DeLong listed_delong(const std::vector<std::vector<double>>& positives,
                     const std::vector<std::vector<double>>& negatives) {
  const std::size_t k = positives.size(), m = positives[0].size(), n = negatives[0].size();
  const double md = static_cast<double>(m), nd = static_cast<double>(n);
  DeLong out;
  std::vector<std::vector<double>> v01(k), v10(k);
  for (std::size_t r = 0; r < k; ++r) {
    std::vector<double> z = positives[r];
    z.insert(z.end(), negatives[r].begin(), negatives[r].end());
    const std::vector<double> tx = average_ranks(positives[r]);
    const std::vector<double> ty = average_ranks(negatives[r]);
    const std::vector<double> tz = average_ranks(z);
    double ranks = 0;
    for (std::size_t i = 0; i < m; ++i) ranks += tz[i];
    out.aucs.push_back(ranks / md / nd - (md + 1.0) / 2.0 / nd);
    for (std::size_t i = 0; i < m; ++i) v01[r].push_back((tz[i] - tx[i]) / nd);
    for (std::size_t j = 0; j < n; ++j) v10[r].push_back(1.0 - (tz[m + j] - ty[j]) / md);
  }
  const auto covariance = [k](const std::vector<std::vector<double>>& v) {
    const std::size_t len = v[0].size();
    std::vector<double> mean(k);
    for (std::size_t r = 0; r < k; ++r) {
      Sum s;
      for (double x : v[r]) s.add(x);
      mean[r] = s.value() / static_cast<double>(len);
    }
    std::vector<double> c(k * k);
    for (std::size_t a = 0; a < k; ++a) {
      for (std::size_t b = a; b < k; ++b) {
        Sum s;
        for (std::size_t i = 0; i < len; ++i) s.add((v[a][i] - mean[a]) * (v[b][i] - mean[b]));
        c[a * k + b] = c[b * k + a] = s.value() / static_cast<double>(len - 1);
      }
    }
    return c;
  };
  const std::vector<double> sx = covariance(v01), sy = covariance(v10);
  for (std::size_t i = 0; i < k * k; ++i) out.cov.push_back(sx[i] / md + sy[i] / nd);
  return out;
}

double listed_percentile_numpy(std::vector<double> x, double p) {
  std::sort(x.begin(), x.end());
  const double h = (static_cast<double>(x.size()) - 1) * p;
  const std::size_t lo = static_cast<std::size_t>(std::floor(h));
  if (lo + 1 >= x.size()) return x.back();
  const double t = h - static_cast<double>(lo), a = x[lo], b = x[lo + 1], diff = b - a;
  return t >= 0.5 ? b - diff * (1 - t) : a + diff * t;
}

double listed_percentile_prctile(std::vector<double> x, double p) {
  std::sort(x.begin(), x.end());
  const double n = static_cast<double>(x.size());
  const double pos = n * p + 0.5;
  if (pos <= 1) return x.front();
  if (pos >= n) return x.back();
  const std::size_t lo = static_cast<std::size_t>(std::floor(pos));
  const double t = pos - static_cast<double>(lo);
  return x[lo - 1] + t * (x[lo] - x[lo - 1]);
}

// Every value of the old krasula_analysis(differences, labels) but the tests between metrics
// (functions of these values, unchanged).
KrasulaResult listed_analysis(const std::vector<std::vector<double>>& differences,
                              const std::vector<int>& labels) {
  const std::size_t k = differences.size(), pairs = labels.size();
  KrasulaResult r;
  for (int l : labels) {
    r.different += l != 0;
    r.better += l == 1;
    r.similar += l == 0;
  }
  std::vector<std::vector<double>> dif(k), sim(k), better(k), worse(k);
  for (std::size_t m = 0; m < k; ++m) {
    for (std::size_t p = 0; p < pairs; ++p) {
      (labels[p] != 0 ? dif : sim)[m].push_back(std::fabs(differences[m][p]));
      if (labels[p] == 1) better[m].push_back(differences[m][p]);
    }
    for (std::size_t p = 0; p < pairs; ++p) {
      if (labels[p] == -1) better[m].push_back(-differences[m][p]);
    }
    for (double b : better[m]) worse[m].push_back(-b);
  }
  const bool ds = r.similar >= 2;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const DeLong delong_ds = ds ? listed_delong(dif, sim) : DeLong{};
  const DeLong delong_bw = listed_delong(better, worse);
  r.cov_ds = ds ? delong_ds.cov : std::vector<double>(k * k, nan);
  r.cov_bw = delong_bw.cov;
  const double l = static_cast<double>(2 * r.different);
  for (std::size_t m = 0; m < k; ++m) {
    KrasulaMetric km;
    km.auc_ds = ds ? delong_ds.aucs[m] : nan;
    km.se_ds = std::sqrt(r.cov_ds[m * k + m]);
    km.auc_bw = delong_bw.aucs[m];
    km.se_bw = std::sqrt(r.cov_bw[m * k + m]);
    std::size_t right = 0;
    for (double b : better[m]) right += b > 0;
    for (double w : worse[m]) right += w < 0;
    km.c0 = static_cast<double>(right) / l;
    km.thr_numpy = sim[m].empty() ? nan : listed_percentile_numpy(sim[m], 0.95);
    km.thr_prctile = sim[m].empty() ? nan : listed_percentile_prctile(sim[m], 0.95);
    r.metrics.push_back(km);
  }
  return r;
}

// ---- the comparison ---------------------------------------------------------------------------

// The same double, bit for bit (NaN == NaN).
void expect_same(double got, double expected, const std::string& what) {
  EXPECT_EQ(std::memcmp(&got, &expected, sizeof got), 0)
      << what << ": " << std::hexfloat << got << " vs " << expected;
}

// Within 1e-12 of `scale` (the project's rule for sums in another order; NaN == NaN).
void expect_close(double got, double expected, double scale, const std::string& what) {
  if (std::isnan(expected)) {
    EXPECT_TRUE(std::isnan(got)) << what << ": " << got;
    return;
  }
  EXPECT_LE(std::fabs(got - expected), 1e-12 * scale)
      << what << ": " << std::hexfloat << got << " vs " << expected;
}

void expect_same_result(const KrasulaResult& got, const KrasulaResult& expected) {
  EXPECT_EQ(got.different, expected.different);
  EXPECT_EQ(got.better, expected.better);
  EXPECT_EQ(got.similar, expected.similar);
  ASSERT_EQ(got.metrics.size(), expected.metrics.size());
  for (std::size_t m = 0; m < got.metrics.size(); ++m) {
    const KrasulaMetric &a = got.metrics[m], &b = expected.metrics[m];
    const std::string at = " of metric " + std::to_string(m);
    expect_same(a.auc_ds, b.auc_ds, "auc_ds" + at);
    expect_same(a.auc_bw, b.auc_bw, "auc_bw" + at);
    expect_close(a.se_ds, b.se_ds, b.se_ds, "se_ds" + at);
    expect_close(a.se_bw, b.se_bw, b.se_bw, "se_bw" + at);
    expect_same(a.c0, b.c0, "c0" + at);
    expect_same(a.thr_numpy, b.thr_numpy, "thr_numpy" + at);
    expect_same(a.thr_prctile, b.thr_prctile, "thr_prctile" + at);
  }
  ASSERT_EQ(got.cov_ds.size(), expected.cov_ds.size());
  const std::size_t k = got.metrics.size();
  for (std::size_t i = 0; i < got.cov_ds.size(); ++i) {
    const std::size_t x = i / k, y = i % k;
    const auto close = [&](const std::vector<double>& g, const std::vector<double>& e,
                           const std::string& what) {
      expect_close(g[i], e[i], std::sqrt(e[x * k + x] * e[y * k + y]), what + std::to_string(i));
    };
    close(got.cov_ds, expected.cov_ds, "cov_ds ");
    close(got.cov_bw, expected.cov_bw, "cov_bw ");
  }
}

// Scores on a coarse grid (many tied differences, zero differences among them) or continuous.
std::vector<std::vector<double>> random_scores(std::mt19937_64& rng, std::size_t metrics,
                                               std::size_t stimuli, bool ties) {
  std::normal_distribution<double> normal;
  std::vector<std::vector<double>> scores(metrics);
  for (auto& s : scores) {
    for (std::size_t i = 0; i < stimuli; ++i) {
      const double x = normal(rng);
      s.push_back(ties ? std::round(x * 3) / 3 : x);
    }
  }
  return scores;
}

// The old differences of the listed pairs.
std::vector<std::vector<double>> listed_differences(const std::vector<std::vector<double>>& scores,
                                                    const PairLabels& pairs) {
  std::vector<std::vector<double>> d(scores.size());
  for (std::size_t m = 0; m < scores.size(); ++m) {
    for (std::size_t p = 0; p < pairs.size(); ++p) {
      d[m].push_back(scores[m][pairs.first(p)] - scores[m][pairs.second(p)]);
    }
  }
  return d;
}

TEST(KrasulaPairs, SortedEqualsListedOnRandomData) {
  std::mt19937_64 rng(37);
  int compared = 0;
  for (int trial = 0; trial < 24; ++trial) {
    const std::size_t stimuli = 6 + rng() % 60, metrics = 1 + rng() % 3;
    const bool ties = trial % 2 == 0;
    std::uniform_real_distribution<double> mos_draw(1, 5), sd_draw(0.2, 1.2);
    std::vector<double> mos, sd, n;
    std::vector<std::vector<double>> raw(stimuli);
    std::vector<std::string> groups;
    for (std::size_t i = 0; i < stimuli; ++i) {
      mos.push_back(ties ? std::round(mos_draw(rng) * 2) / 2 : mos_draw(rng));
      sd.push_back(trial % 5 == 0 ? 0.0 : sd_draw(rng));
      n.push_back(static_cast<double>(8 + rng() % 20));
      for (int k = 0; k < 6; ++k) raw[i].push_back(mos.back() + sd_draw(rng) * (k % 3 - 1));
      groups.push_back(std::string(1, static_cast<char>('a' + rng() % 3)));
    }
    const std::vector<std::vector<double>> scores = random_scores(rng, metrics, stimuli, ties);
    const std::vector<std::string> none;
    for (const PairLabels& pairs : {label_pairs_j149(mos, sd, n, trial % 3 == 0 ? groups : none),
                                    label_pairs_raw(raw, trial % 3 == 1 ? groups : none)}) {
      std::size_t different = 0;
      for (auto l : pairs.label) different += l != 0;
      if (different < 2) continue;
      SCOPED_TRACE("trial " + std::to_string(trial) + ", " + pairs.rule);
      const std::vector<int> labels(pairs.label.begin(), pairs.label.end());
      const auto d = listed_differences(scores, pairs);
      const KrasulaResult expected = listed_analysis(d, labels);
      expect_same_result(krasula_analysis(scores, pairs), expected);
      expect_same_result(krasula_analysis(d, labels), expected);
      ++compared;
    }
  }
  EXPECT_GT(compared, 30);
}

// More pairs than one block of the analysis (2^18): the sweeps restart with each block.
TEST(KrasulaPairs, SortedEqualsListedOverSeveralBlocks) {
  std::mt19937_64 rng(371);
  const std::size_t stimuli = 800;  // 319,600 pairs
  std::uniform_real_distribution<double> mos_draw(1, 5), sd_draw(0.3, 1.2);
  std::vector<double> mos, sd, n(stimuli, 15);
  for (std::size_t i = 0; i < stimuli; ++i) {
    mos.push_back(mos_draw(rng));
    sd.push_back(sd_draw(rng));
  }
  const std::vector<std::vector<double>> scores = random_scores(rng, 2, stimuli, true);
  const PairLabels pairs = label_pairs_j149(mos, sd, n);
  ASSERT_GT(pairs.size(), std::size_t(1) << 18);
  const std::vector<int> labels(pairs.label.begin(), pairs.label.end());
  expect_same_result(krasula_analysis(scores, pairs),
                     listed_analysis(listed_differences(scores, pairs), labels));
}

// Scores whose differences crowd a few of the lookup index's buckets (an outlier stretching the
// range, a constant metric, values near the smallest doubles, heavy ties): the counts only read
// a value's own bucket, so a crowded or empty bucket must still give every listed value.
TEST(KrasulaPairs, SortedEqualsListedOnCrowdedBuckets) {
  std::mt19937_64 rng(3737);
  const std::size_t stimuli = 700;  // 244,650 pairs
  std::uniform_real_distribution<double> mos_draw(1, 5), sd_draw(0.3, 1.2);
  std::normal_distribution<double> normal;
  std::vector<double> mos, sd, n(stimuli, 15);
  std::vector<std::vector<double>> scores(4);
  for (std::size_t i = 0; i < stimuli; ++i) {
    mos.push_back(mos_draw(rng));
    sd.push_back(sd_draw(rng));
    scores[0].push_back(i == 17 ? 1e6 : normal(rng));                 // one outlier
    scores[1].push_back(2.5);                                         // constant: every d is 0
    scores[2].push_back(std::ldexp(normal(rng), -1060));              // subnormal differences
    scores[3].push_back(i % 7 == 0 ? 1e3 : std::round(normal(rng)));  // ties, two clusters
  }
  const PairLabels pairs = label_pairs_j149(mos, sd, n);
  const std::vector<int> labels(pairs.label.begin(), pairs.label.end());
  expect_same_result(krasula_analysis(scores, pairs),
                     listed_analysis(listed_differences(scores, pairs), labels));
}

// The generated layouts are the pairs the nested loops list, in their order.
TEST(KrasulaPairs, GeneratedPairsAreTheListedOnes) {
  const std::vector<std::string> groups = {"b", "a", "b", "b", "a", "c"};
  const std::vector<double> mos = {1, 2, 3, 4, 5, 6}, sd(6, 0.1), n(6, 10);
  const PairLabels j149 = label_pairs_j149(mos, sd, n, groups);
  std::vector<std::pair<std::size_t, std::size_t>> expected, got;
  for (std::size_t j = 1; j < 6; ++j) {
    for (std::size_t i = 0; i < j; ++i) {
      if (groups[i] == groups[j]) expected.emplace_back(j, i);
    }
  }
  j149.for_each([&](std::size_t a, std::size_t b) { got.emplace_back(a, b); });
  EXPECT_EQ(got, expected);
  ASSERT_EQ(j149.size(), expected.size());
  for (std::size_t p = 0; p < expected.size(); ++p) {
    EXPECT_EQ(j149.first(p), expected[p].first);
    EXPECT_EQ(j149.second(p), expected[p].second);
  }
  std::vector<std::vector<double>> raw(6, std::vector<double>{1, 2});
  const PairLabels all = label_pairs_raw(raw, groups);
  expected.clear();
  got.clear();
  for (std::size_t i = 0; i < 6; ++i) {
    for (std::size_t j = 0; j < 6; ++j) {
      if (groups[i] == groups[j]) expected.emplace_back(i, j);
    }
  }
  all.for_each([&](std::size_t a, std::size_t b) { got.emplace_back(a, b); });
  EXPECT_EQ(got, expected);
  EXPECT_EQ(all.size(), expected.size());
  EXPECT_EQ(all.stimuli_named(), 6u);
}

}  // namespace
}  // namespace qm3d
