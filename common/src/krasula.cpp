#include "qm3d/common/krasula.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "qm3d/common/evaluation.h"
#include "qm3d/common/p1401.h"  // two_sided_normal_p

namespace qm3d {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

bool same_group(const std::vector<std::string>& groups, std::size_t a, std::size_t b) {
  return groups.empty() || groups[a] == groups[b];
}

// Neumaier's compensated sum: the order-independent accuracy of numpy's pairwise sums and
// better, so that the means and covariances agree with VMAF's to ~1e-16 relative.
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

// Sun & Xu's fastDeLong on k rows of m positive then n negative ratings: each row's AUC and the
// k x k DeLong covariance (sx / m + sy / n, sx and sy the sample covariances, N - 1, of the
// structural components v01 and v10).
struct DeLong {
  std::vector<double> aucs, cov;
};

DeLong fast_delong(const std::vector<std::vector<double>>& positives,
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
    double ranks = 0;  // a sum of half-integers below 2^52: exact in any order
    for (std::size_t i = 0; i < m; ++i) ranks += tz[i];
    out.aucs.push_back(ranks / md / nd - (md + 1.0) / 2.0 / nd);
    v01[r].resize(m);
    v10[r].resize(n);
    for (std::size_t i = 0; i < m; ++i) v01[r][i] = (tz[i] - tx[i]) / nd;
    for (std::size_t j = 0; j < n; ++j) v10[r][j] = 1.0 - (tz[m + j] - ty[j]) / md;
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
  out.cov.resize(k * k);
  for (std::size_t i = 0; i < k * k; ++i) out.cov[i] = sx[i] / md + sy[i] / nd;
  return out;
}

// numpy.percentile's default ("linear": position (n - 1) p between the sorted values, with
// numpy's _lerp, which interpolates from the upper value when t >= 0.5).
double percentile_numpy(std::vector<double> x, double p) {
  std::sort(x.begin(), x.end());
  const double h = (static_cast<double>(x.size()) - 1) * p;
  const std::size_t lo = static_cast<std::size_t>(std::floor(h));
  if (lo + 1 >= x.size()) return x.back();
  const double t = h - static_cast<double>(lo), a = x[lo], b = x[lo + 1], diff = b - a;
  return t >= 0.5 ? b - diff * (1 - t) : a + diff * t;
}

// MATLAB's / Octave's prctile (Hazen): x_(k) at p = (k - 0.5) / n, linear between, the extremes
// beyond.
double percentile_prctile(std::vector<double> x, double p) {
  std::sort(x.begin(), x.end());
  const double n = static_cast<double>(x.size());
  const double pos = n * p + 0.5;  // 1-based
  if (pos <= 1) return x.front();
  if (pos >= n) return x.back();
  const std::size_t lo = static_cast<std::size_t>(std::floor(pos));
  const double t = pos - static_cast<double>(lo);
  return x[lo - 1] + t * (x[lo] - x[lo - 1]);
}

double delong_z(const std::vector<double>& aucs, const std::vector<double>& cov, std::size_t k,
                std::size_t a, std::size_t b) {
  const double var = cov[a * k + a] + cov[b * k + b] - 2 * cov[a * k + b];
  return std::fabs(aucs[a] - aucs[b]) / std::sqrt(var);
}

}  // namespace

PairLabels label_pairs_j149(const std::vector<double>& mos, const std::vector<double>& sd,
                            const std::vector<double>& n, const std::vector<std::string>& groups) {
  const std::size_t count = mos.size();
  require(sd.size() == count && n.size() == count, "pair labels: MOS, SD and n differ in length");
  require(groups.empty() || groups.size() == count, "pair labels: one group per stimulus needed");
  require(count >= 2, "pair labels: at least 2 stimuli needed");
  for (std::size_t i = 0; i < count; ++i) {
    require(std::isfinite(mos[i]) && std::isfinite(sd[i]) && std::isfinite(n[i]),
            "pair labels: stimulus " + std::to_string(i + 1) + " has a non-finite MOS, SD or n");
    require(sd[i] >= 0, "pair labels: stimulus " + std::to_string(i + 1) + " has a negative SD");
    require(n[i] >= 2, "pair labels: stimulus " + std::to_string(i + 1) +
                           " has fewer than 2 observers (n)");
  }
  PairLabels pairs;
  pairs.rule = "one-sided 95 % z test of the MOS difference, SE = sqrt(SD1^2/n1 + SD2^2/n2) "
               "(Krasula; ITU-T J.149)";
  for (std::size_t j = 1; j < count; ++j) {
    for (std::size_t i = 0; i < j; ++i) {
      if (!same_group(groups, i, j)) continue;
      double se = std::sqrt(sd[j] * sd[j] / n[j] + sd[i] * sd[i] / n[i]);
      if (se == 0) se = 1e-6;
      const double diff = mos[j] - mos[i];
      const double z = diff / se;
      const bool significant = 0.5 + std::erf(std::fabs(z) / std::sqrt(2.0)) / 2 >= 0.95;
      pairs.add(j, i, significant ? (diff > 0) - (diff < 0) : 0);
    }
  }
  return pairs;
}

PairLabels label_pairs_raw(const std::vector<std::vector<double>>& scores,
                           const std::vector<std::string>& groups) {
  const std::size_t count = scores.size();
  require(count >= 2, "pair labels: at least 2 stimuli needed");
  require(groups.empty() || groups.size() == count, "pair labels: one group per stimulus needed");
  std::vector<double> mean(count), var_over_n(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::vector<double>& s = scores[i];
    require(s.size() >= 2, "pair labels: stimulus " + std::to_string(i + 1) +
                               " has fewer than 2 individual scores");
    Sum sum;
    for (double x : s) {
      require(std::isfinite(x), "pair labels: stimulus " + std::to_string(i + 1) +
                                    " has a non-finite score");
      sum.add(x);
    }
    const double len = static_cast<double>(s.size());
    mean[i] = sum.value() / len;
    Sum squares;
    for (double x : s) squares.add((x - mean[i]) * (x - mean[i]));
    var_over_n[i] = squares.value() / (len - 1) / len;
  }
  PairLabels pairs;
  pairs.rule = "two-sided z test |z| > 2 of the mean difference, var with N-1, every ordered "
               "pair and self-pair (VMAF AucPerfMetric)";
  for (std::size_t i = 0; i < count; ++i) {
    for (std::size_t j = 0; j < count; ++j) {
      if (!same_group(groups, i, j)) continue;
      double den = var_over_n[i] + var_over_n[j];
      if (den == 0) den = 1e-8;
      const double z = (mean[i] - mean[j]) / std::sqrt(den);
      pairs.add(i, j, z > 2 ? 1 : z < -2 ? -1 : 0);
    }
  }
  return pairs;
}

KrasulaResult krasula_analysis(const std::vector<std::vector<double>>& differences,
                               const std::vector<int>& labels) {
  const std::size_t k = differences.size(), pairs = labels.size();
  require(k >= 1, "Krasula analysis: no metric");
  for (const auto& d : differences) {
    require(d.size() == pairs, "Krasula analysis: a metric's differences and the labels differ "
                               "in length");
    for (double x : d) require(std::isfinite(x), "Krasula analysis: a non-finite difference");
  }
  KrasulaResult r;
  for (int l : labels) {
    require(l == -1 || l == 0 || l == 1, "Krasula analysis: a label other than -1, 0, 1");
    r.different += l != 0;
    r.better += l == 1;
    r.similar += l == 0;
  }
  require(r.different >= 2, "Krasula analysis: " + std::to_string(r.different) +
                                " significantly different pairs; at least 2 needed");
  // D = |d| of the different pairs, S = |d| of the similar ones; B = d of the pairs labelled 1,
  // then -d of those labelled -1 (Metrics_performance.m's order), W = -B.
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
  const DeLong delong_ds = ds ? fast_delong(dif, sim) : DeLong{};
  const DeLong delong_bw = fast_delong(better, worse);
  r.cov_ds = ds ? delong_ds.cov : std::vector<double>(k * k, kNaN);
  r.cov_bw = delong_bw.cov;
  const double l = static_cast<double>(2 * r.different);
  for (std::size_t m = 0; m < k; ++m) {
    KrasulaMetric km;
    km.auc_ds = ds ? delong_ds.aucs[m] : kNaN;
    km.se_ds = std::sqrt(r.cov_ds[m * k + m]);
    km.auc_bw = delong_bw.aucs[m];
    km.se_bw = std::sqrt(r.cov_bw[m * k + m]);
    std::size_t right = 0;
    for (double b : better[m]) right += b > 0;
    for (double w : worse[m]) right += w < 0;
    km.c0 = static_cast<double>(right) / l;
    km.thr_numpy = sim[m].empty() ? kNaN : percentile_numpy(sim[m], 0.95);
    km.thr_prctile = sim[m].empty() ? kNaN : percentile_prctile(sim[m], 0.95);
    r.metrics.push_back(km);
  }
  for (std::size_t a = 0; a < k; ++a) {
    for (std::size_t b = a + 1; b < k; ++b) {
      KrasulaComparison c;
      c.a = a;
      c.b = b;
      c.cov_ds = r.cov_ds[a * k + b];
      c.cov_bw = r.cov_bw[a * k + b];
      c.z_delong_ds = ds ? delong_z(delong_ds.aucs, r.cov_ds, k, a, b) : kNaN;
      c.p_delong_ds = ds ? two_sided_normal_p(c.z_delong_ds) : kNaN;
      c.z_delong_bw = delong_z(delong_bw.aucs, r.cov_bw, k, a, b);
      c.p_delong_bw = two_sided_normal_p(c.z_delong_bw);
      const double c0a = r.metrics[a].c0, c0b = r.metrics[b].c0, pbar = (c0a + c0b) / 2.0;
      // Equal proportions (both 1, say, where the pooled variance is 0) are no evidence of a
      // difference: z = 0, p = 1 (VMAF's formula gives 0/0 there).
      c.z_c0 = c0a == c0b ? 0.0 : std::fabs(c0a - c0b) / std::sqrt(pbar * (1.0 - pbar) * 2.0 / l);
      c.p_c0 = two_sided_normal_p(c.z_c0);
      r.comparisons.push_back(c);
    }
  }
  return r;
}

KrasulaResult krasula_analysis(const std::vector<std::vector<double>>& scores,
                               const PairLabels& pairs) {
  std::vector<std::vector<double>> differences(scores.size());
  for (std::size_t m = 0; m < scores.size(); ++m) {
    for (std::size_t p = 0; p < pairs.size(); ++p) {
      require(pairs.first[p] < scores[m].size() && pairs.second[p] < scores[m].size(),
              "Krasula analysis: a pair names a stimulus the scores do not have");
      differences[m].push_back(scores[m][pairs.first[p]] - scores[m][pairs.second[p]]);
    }
  }
  return krasula_analysis(differences, pairs.label);
}

}  // namespace qm3d
