// Krasula et al.'s analysis of objective metrics on pairs of stimuli (L. Krasula, K. Fliegel,
// P. Le Callet, M. Klima, "On the accuracy of objective image and video quality models: New
// methodology for performance evaluation", QoMEX 2016): AUC_DS (can the metric tell significantly
// different pairs from similar ones?), AUC_BW (does it tell which of a different pair is
// better?), C0 (the share of different pairs it orders correctly) and THR (the score difference
// that 95 % of the similar pairs stay below), with DeLong's covariance of the AUCs (Sun & Xu's
// fast algorithm, IEEE SPL 2014) and the tests between metrics.
//
// Numbers as krasuluk/AucPerformance (Metrics_performance.m, fastDeLong.m, @ 2821dc8) and
// Netflix/vmaf (python/vmaf/core/perf_metric.py AucPerfMetric, python/vmaf/tools/sigproc.py,
// @ f85a853) compute them; the conventions are in ../shared/data/reference/evaluation/README.md.
//
// Example:
//   const qm3d::evaluation::PairLabels pairs = qm3d::evaluation::label_pairs_j149(mos, sd, n);
//   const qm3d::evaluation::KrasulaResult r =
//       qm3d::evaluation::krasula_analysis({psnr, ssim}, pairs);
//   // r.metrics[1].auc_bw, r.comparisons[0].p_delong_bw ...
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace qm3d::evaluation {

/// Pairs of stimuli with their subjective outcome: label +1 = the first stimulus is
/// significantly better than the second, -1 = significantly worse, 0 = not significantly
/// different. One byte a pair: pairs given one by one (add()) keep their two indices, the pairs
/// label_pairs_j149() and label_pairs_raw() make are generated from the stimuli and their groups
/// whenever they are needed, so that 10,000 stimuli (50 M pairs) take 50 MB.
struct PairLabels {
 public:
  std::vector<std::int8_t> label;  ///< of each pair, in pair order
  /// How the labels were made, for the output ("J.149 one-sided 95 % z test on MOS, SD, n").
  std::string rule;
  std::size_t size() const { return label.size(); }
  /// Appends a given pair (a and b below 2^32).
  void add(std::size_t a, std::size_t b, int l);
  std::size_t first(std::size_t p) const;   ///< stimulus index of pair p's first
  std::size_t second(std::size_t p) const;  ///< ... and of its second
  /// 1 + the largest stimulus index a pair names (0 without pairs).
  std::size_t stimuli_named() const;
  /// Calls f(first, second) for every pair, in pair order (the order of `label`).
  template <class F>
  void for_each(F&& f) const;

  /// The pair layouts label_pairs_j149() and label_pairs_raw() generate over stimuli whose
  /// groups are `group_of` (group ids; all 0 for one group): every (j, i) with i < j of one
  /// group, by j then i (kLowerTriangle), or every (i, j) of one group, self-pairs included, by i
  /// then j (kAllOrdered). The labels are left to the caller (size() pairs, in that order).
  enum class Layout { kGiven, kLowerTriangle, kAllOrdered };
  static PairLabels generated(Layout layout, const std::vector<std::uint32_t>& group_of);
  /// The number of pairs of the layout (the labels to append).
  std::size_t pair_count() const;

 private:
  std::size_t partners(std::size_t row) const;  // pairs whose first is `row`
  Layout layout_ = Layout::kGiven;
  std::vector<std::uint32_t> first_, second_;  // kGiven
  // Generated: each stimulus' group and place in it; the groups' members ascending, one block
  // per group (member_start_); the first pair of each row (stimulus), then the total.
  std::vector<std::uint32_t> group_of_, place_, members_;
  std::vector<std::size_t> member_start_, row_start_;
};

template <class F>
void PairLabels::for_each(F&& f) const {
  if (layout_ == Layout::kGiven) {
    for (std::size_t p = 0; p < first_.size(); ++p)
      f(std::size_t(first_[p]), std::size_t(second_[p]));
    return;
  }
  for (std::size_t row = 0; row < group_of_.size(); ++row) {
    const std::uint32_t* m = members_.data() + member_start_[group_of_[row]];
    const std::size_t n = partners(row);
    for (std::size_t k = 0; k < n; ++k) f(row, std::size_t(m[k]));
  }
}

/// Krasula's labels from per-stimulus MOS, standard deviation and observer count
/// (Example_preprocess_and_calculate_performance.m; ITU-T J.149 style): for a pair,
/// z = (MOS_first - MOS_second) / SE with SE = sqrt(SD_first^2 / n_first + SD_second^2 / n_second)
/// (1e-6 where SE = 0), label = sign(MOS difference) when 1/2 + erf(|z| / sqrt 2) / 2 >= 0.95
/// (a one-sided 95 % test), else 0. Pairs: every unordered pair once, as (first, second) =
/// (j, i) for j > i ordered by j then i (the order of the VMAF test vectors); with `groups`
/// (one value per stimulus) only pairs within a group (the BASICS intra-source track).
/// @throws std::invalid_argument  lengths differ, fewer than 2 stimuli, a non-finite value, a
///                                negative SD or n < 2
PairLabels label_pairs_j149(const std::vector<double>& mos, const std::vector<double>& sd,
                            const std::vector<double>& n,
                            const std::vector<std::string>& groups = {});

/// Labels from each stimulus' individual scores as VMAF's AucPerfMetric makes them: every
/// ordered pair (i, j) of the N stimuli, the N self-pairs included (N^2 pairs, row-major),
/// z = (mean_i - mean_j) / sqrt(var_i / n_i + var_j / n_j) (var with N - 1; denominator 1e-8
/// where it is 0), label +1 for z > 2, -1 for z < -2, else 0. With `groups`, pairs outside a
/// group are left out.
/// @throws std::invalid_argument  fewer than 2 stimuli, a stimulus with fewer than 2 scores, a
///                                non-finite score
PairLabels label_pairs_raw(const std::vector<std::vector<double>>& scores,
                           const std::vector<std::string>& groups = {});

/// One metric's results. Differences are d = score(first) - score(second), the scores oriented
/// higher = better (a distortion is negated by the caller).
struct KrasulaMetric {
  double auc_ds = 0;  ///< Mann-Whitney AUC of |d| on different pairs against similar ones
  double auc_bw = 0;  ///< AUC of B = d * label (different pairs) against W = -B
  double c0 = 0;      ///< #{B > 0} / #different (a zero difference counts as wrong)
  /// 95th percentile of |d| over the similar pairs: numpy's default rule (linear, position
  /// (n - 1) p; VMAF) and MATLAB's prctile (Hazen: x_(k) at p = (k - 0.5) / n; Krasula).
  double thr_numpy = 0, thr_prctile = 0;
  double se_ds = 0, se_bw = 0;  ///< DeLong standard errors (square roots of the diagonals)
};

/// A test between two metrics.
struct KrasulaComparison {
  std::size_t a = 0, b = 0;       ///< metric indices, a < b
  double cov_ds = 0, cov_bw = 0;  ///< DeLong covariances of the two metrics' AUCs
  /// DeLong's test: z = |AUC_a - AUC_b| / sqrt(C_aa + C_bb - 2 C_ab), p = 2 (1 - Phi(z)).
  double z_delong_ds = 0, p_delong_ds = 1, z_delong_bw = 0, p_delong_bw = 1;
  /// C0's two-proportion (binomial) test: pbar = (C0_a + C0_b) / 2,
  /// z = |C0_a - C0_b| / sqrt(pbar (1 - pbar) 2 / L) with L = 2 #different, p two-sided.
  double z_c0 = 0, p_c0 = 1;
};

struct KrasulaResult {
  std::size_t different = 0;  ///< pairs labelled +1 or -1
  std::size_t better = 0;     ///< labelled +1
  std::size_t similar = 0;    ///< labelled 0
  std::vector<KrasulaMetric> metrics;
  std::vector<KrasulaComparison> comparisons;  ///< every a < b, in order (0,1), (0,2), ...
  /// DeLong covariance matrices (metrics x metrics, row-major).
  std::vector<double> cov_ds, cov_bw;
};

/// The analysis of `differences[m][p]` (metric m, pair p: d = score(first) - score(second),
/// higher = better) against `labels[p]`.
/// With fewer than 2 similar pairs the DS values (AUC_DS, its SE and tests, THR) are NaN.
/// Cost: the pairs are never listed per metric as Mann-Whitney / DeLong would; each metric's
/// |d| and B values are sorted once (8 bytes a pair and metric: 50 M pairs, 400 MB a metric).
/// A pair's structural component (the share of the other class below it, ties counting half)
/// is an integer count over twice the class size, so the AUCs and DeLong's covariances are exact
/// integer sums: a metric's own values are summed over the distinct values of its sorted arrays
/// (O(P log P) for the sort, linear after it); the covariances between metrics need each pair's
/// counts under both, found for blocks of pairs sorted by |d| sweeping the sorted arrays (with 2
/// metrics or more only). Exact sums: the same bits for any number of threads.
/// @throws std::invalid_argument  lengths differ, a non-finite difference, a label other than
///                                -1, 0, 1, fewer than 2 different pairs or 2^31 pairs or more
KrasulaResult krasula_analysis(const std::vector<std::vector<double>>& differences,
                               const std::vector<int>& labels);

/// The same from per-stimulus scores (`scores[m][i]`, oriented higher = better) and the pairs.
KrasulaResult krasula_analysis(const std::vector<std::vector<double>>& scores,
                               const PairLabels& pairs);

}  // namespace qm3d::evaluation
