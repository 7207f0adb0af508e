#include "qm3d/evaluation/krasula.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <parallel/algorithm>
#include <stdexcept>

#include "qm3d/evaluation/evaluation.h"
#include "qm3d/evaluation/p1401.h"  // two_sided_normal_p

namespace qm3d::evaluation {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// |z| below / above which J.149's one-sided 95 % test is certain without evaluating it.
constexpr double kSurelyNot = 1.6, kSurelySignificant = 1.7;

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
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

// numpy.percentile's default ("linear": position (n - 1) p between the sorted values, with
// numpy's _lerp, which interpolates from the upper value when t >= 0.5).
double percentile_numpy(const std::vector<double>& x, double p) {  // x sorted
  const double h = (static_cast<double>(x.size()) - 1) * p;
  const std::size_t lo = static_cast<std::size_t>(std::floor(h));
  if (lo + 1 >= x.size()) return x.back();
  const double t = h - static_cast<double>(lo), a = x[lo], b = x[lo + 1], diff = b - a;
  return t >= 0.5 ? b - diff * (1 - t) : a + diff * t;
}

// MATLAB's / Octave's prctile (Hazen): x_(k) at p = (k - 0.5) / n, linear between, the extremes
// beyond.
double percentile_prctile(const std::vector<double>& x, double p) {  // x sorted
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

// ---- one metric's sorted values and the structural components counted in them -------------

// Counting in a sorted array at ascending query values: each search starts where the last one
// ended and gallops forward (exponential, then binary search), so that a block of queries,
// sorted, sweeps the array once, reading it nearly in order instead of ~25 cache lines a query.
class Sweep {
 public:
  explicit Sweep(const std::vector<double>& sorted) : v_(sorted) {}
  // {#{values < x}, #{values == x}}; x at least the previous query's.
  std::pair<std::uint64_t, std::uint64_t> below_and_equal(double x) {
    at_ = gallop(at_, [x](double v) { return v < x; });
    const std::size_t not_above = gallop(at_, [x](double v) { return v <= x; });
    return {at_, not_above - at_};
  }

 private:
  // The first index from `from` on whose value fails `before` (which holds for a prefix).
  template <class Before>
  std::size_t gallop(std::size_t from, Before before) const {
    std::size_t lo = from, hi = from, step = 1;
    while (hi < v_.size() && before(v_[hi])) {
      lo = hi + 1;
      hi += step;
      step *= 2;
    }
    hi = std::min(hi, v_.size());
    return static_cast<std::size_t>(
        std::partition_point(v_.begin() + static_cast<std::ptrdiff_t>(lo),
                             v_.begin() + static_cast<std::ptrdiff_t>(hi), before) -
        v_.begin());
  }
  const std::vector<double>& v_;
  std::size_t at_ = 0;
};

// One metric's values, sorted: |d| of the similar pairs (S), and B (d of the pairs labelled 1,
// -d of those labelled -1) split by sign, so that the different pairs' |d| (D = |B|) and B
// itself are both counted in the same two arrays.
struct SortedValues {
  std::vector<double> similar;   // S, ascending
  std::vector<double> positive;  // B > 0, ascending
  std::vector<double> negative;  // -B for B < 0, ascending
  std::uint64_t zeros = 0;       // B == 0
};

// The structural-component counts of one metric's pairs, at their |d| in ascending order (a
// sweep of each array). Twice the Mann-Whitney counts (ties half), exact integers:
// DS, a different pair's |d| = x against S: 2 #{S < x} + #{S == x};
// DS, a similar pair's |d| = y against D = |B|: 2 #{D < y} + #{D == y};
// BW, a B value b against W = -B: 2 #{W < b} + #{W == b} = 2 #{B > -b} + #{B == -b}.
class Counter {
 public:
  explicit Counter(const SortedValues& s)
      : s_(s), similar_(s.similar), positive_(s.positive), negative_(s.negative) {}
  std::uint64_t ds_different(double x) {
    const auto [less, equal] = similar_.below_and_equal(x);
    return 2 * less + equal;
  }
  std::uint64_t ds_similar(double y) {
    const auto [pl, pe] = positive_.below_and_equal(y);
    const auto [nl, ne] = negative_.below_and_equal(y);
    return 2 * (pl + nl) + pe + ne + (y > 0 ? 2 : 1) * s_.zeros;
  }
  std::uint64_t bw(double b) {  // |b| at least the previous query's
    const std::uint64_t pos = s_.positive.size();
    if (b > 0) {  // -b < 0: every B >= 0, and the negative ones above -b (|B| < b)
      const auto [less, equal] = negative_.below_and_equal(b);
      return 2 * (pos + s_.zeros + less) + equal;
    }
    if (b < 0) {  // -b > 0: the positive B above -b
      const auto [less, equal] = positive_.below_and_equal(-b);
      return 2 * (pos - less - equal) + equal;
    }
    return 2 * pos + s_.zeros;
  }

 private:
  const SortedValues& s_;
  Sweep similar_, positive_, negative_;
};

// Pairs in blocks: fn(begin, count, d) with d[m * count + i] metric m's difference of pair
// begin + i, for consecutive blocks in pair order.
using BlockFn = std::function<void(std::size_t begin, std::size_t count, const double* d)>;
using PairBlocks = std::function<void(const BlockFn&)>;
// Large enough that a block's sorted queries are dense in the sorted arrays (a sweep reads them
// nearly in order), small enough to stay a few MB.
constexpr std::size_t kBlock = std::size_t(1) << 18;

// The structural components of Sun & Xu's fastDeLong (IEEE SPL 2014) of one list of ratings
// are v01 = (tz - tx) / n for the positives and v10 = 1 - (tz - ty) / m for the negatives: a
// rating's mid-rank among the other class, c / 2 with c the twice-counts above (an integer), over
// the other class' size. Their sample covariances (N - 1) between metrics are therefore those of
// the integers c, scaled: cov(v_a, v_b) = cov(c_a, c_b) / (4 size^2), and
// cov(c_a, c_b) = (L sum c_a c_b - sum c_a sum c_b) / (L (L - 1)) over the list's L ratings is
// an exact integer fraction (128-bit sums, exact below kMaxPairs pairs).
// Exact sums do not depend on their order: the same bits on any number of threads, and the
// diagonal (one metric) needs no pair order at all: it is summed over the distinct values of the
// sorted arrays, each with its multiplicity.
using Int128 = __int128;

// Below 2^31 pairs, every sum below fits: c < 2^32, sum c_a c_b < 2^95, L times it < 2^126.
constexpr std::size_t kMaxPairs = std::size_t(1) << 31;

// One list's sums: L, sum c under each metric, sum c_a c_b for a <= b (row-major k x k).
struct CountSums {
  explicit CountSums(std::size_t metrics) : k(metrics), sum(metrics), cross(metrics * metrics) {}
  std::size_t k;
  std::uint64_t count = 0;
  std::vector<Int128> sum, cross;
  void merge(const CountSums& o) {
    count += o.count;
    for (std::size_t i = 0; i < k; ++i) sum[i] += o.sum[i];
    for (std::size_t i = 0; i < k * k; ++i) cross[i] += o.cross[i];
  }
  // cov(c_a, c_b) / (4 size^2): the covariance of the components.
  double covariance(std::size_t a, std::size_t b, double size) const {
    const Int128 l = static_cast<Int128>(count);
    const Int128 num = l * cross[a * k + b] - sum[a] * sum[b];
    const double pairs = static_cast<double>(count);
    return static_cast<double>(num) / (pairs * (pairs - 1)) / (4 * size * size);
  }
};

// The distinct values of a sorted multiset, ascending, each with its multiplicity: `zeros`
// zeros and up to two ascending arrays of values >= 0.
class Distinct {
 public:
  Distinct(const std::vector<double>& a, const std::vector<double>* b, std::uint64_t zeros)
      : a_(a), b_(b != nullptr ? *b : empty_), zeros_(zeros) {}
  bool next(double& x, std::uint64_t& count) {
    const double inf = std::numeric_limits<double>::infinity();
    x = std::min(i_ < a_.size() ? a_[i_] : inf, j_ < b_.size() ? b_[j_] : inf);
    if (zeros_ > 0) x = 0;
    if (x == inf) return false;
    count = x == 0 ? zeros_ : 0;
    if (x == 0) zeros_ = 0;
    for (; i_ < a_.size() && a_[i_] == x; ++i_) ++count;
    for (; j_ < b_.size() && b_[j_] == x; ++j_) ++count;
    return true;
  }

 private:
  static inline const std::vector<double> empty_{};
  const std::vector<double>& a_;
  const std::vector<double>& b_;
  std::uint64_t zeros_;
  std::size_t i_ = 0, j_ = 0;
};

// One metric's lists summed over its sorted values: DS's different pairs (|d| against S), its
// similar pairs (against D) and BW's B values (against W = -B): sum c and sum c^2 each.
struct MetricSums {
  std::uint64_t ds_different = 0, ds_similar = 0, bw = 0;    // sum c
  Int128 ds_different_sq = 0, ds_similar_sq = 0, bw_sq = 0;  // sum c^2
};

MetricSums sweep_sorted(const SortedValues& s, bool ds) {
  MetricSums r;
  double x = 0;
  std::uint64_t w = 0;
  const auto add = [&w](std::uint64_t c, std::uint64_t& sum, Int128& sq) {
    sum += w * c;
    sq += static_cast<Int128>(w) * c * c;
  };
  if (ds) {
    Counter different(s), similar(s);
    for (Distinct d(s.positive, &s.negative, s.zeros); d.next(x, w);) {
      add(different.ds_different(x), r.ds_different, r.ds_different_sq);
    }
    for (Distinct d(s.similar, nullptr, 0); d.next(x, w);) {
      add(similar.ds_similar(x), r.ds_similar, r.ds_similar_sq);
    }
  }
  Counter above(s), below(s);  // B > 0 (queries the negative array), B < 0 (the positive one)
  for (Distinct d(s.positive, nullptr, 0); d.next(x, w);) add(above.bw(x), r.bw, r.bw_sq);
  for (Distinct d(s.negative, nullptr, 0); d.next(x, w);) add(below.bw(-x), r.bw, r.bw_sq);
  w = s.zeros;
  add(below.bw(0), r.bw, r.bw_sq);
  return r;
}

struct Analysis {
  std::size_t k = 0, different = 0, similar = 0;
  bool ds = false;
  std::vector<SortedValues> sorted;
  // The three lists' sums: DS's different pairs, its similar pairs, BW's B values.
  CountSums ds_different, ds_similar, bw;
  explicit Analysis(std::size_t metrics)
      : k(metrics), ds_different(metrics), ds_similar(metrics), bw(metrics) {}
};

// One block's counts of metric m (its differences dm), found in the order of the pairs' |d|
// (one sweep of each sorted array; the order split between threads): ds[i] for every pair (when
// DS is analysed), bw[i] for the different ones.
void count_block(const Analysis& a, std::size_t m, const std::int8_t* label, std::size_t count,
                 const double* dm, std::uint32_t* ds, std::uint32_t* bw) {
  std::vector<std::pair<double, std::uint32_t>> order;  // (|d|, pair in the block)
  order.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    if (a.ds || label[i] != 0) order.emplace_back(std::fabs(dm[i]), static_cast<std::uint32_t>(i));
  }
  __gnu_parallel::sort(order.begin(), order.end());  // unique keys: one result
  const auto parts = static_cast<std::ptrdiff_t>(std::min<std::size_t>(
      static_cast<std::size_t>(omp_get_max_threads()), 1 + order.size() / 4096));
#pragma omp parallel for schedule(static, 1)
  for (std::ptrdiff_t part = 0; part < parts; ++part) {
    const auto at = [&](std::ptrdiff_t p) {
      return order.size() * static_cast<std::size_t>(p) / static_cast<std::size_t>(parts);
    };
    Counter counter(a.sorted[m]);  // its first search gallops from 0
    for (std::size_t o = at(part); o < at(part + 1); ++o) {
      const std::uint32_t i = order[o].second;
      const int l = label[i];
      const double x = dm[i];
      const double ax = std::fabs(x);  // counts below 2^32 (kMaxPairs)
      if (a.ds) {
        ds[i] =
            static_cast<std::uint32_t>(l != 0 ? counter.ds_different(ax) : counter.ds_similar(ax));
      }
      if (l != 0) bw[i] = static_cast<std::uint32_t>(counter.bw(l == 1 ? x : -x));
    }
  }
}

// The cross sums sum c_a c_b (a < b) of the three lists, pair by pair (needed with 2 metrics or
// more): exact integer sums, so the blocks' parts are summed in any order.
void cross_pass(Analysis& a, const std::vector<std::int8_t>& labels, const PairBlocks& pairs) {
  const std::size_t k = a.k;
  std::vector<std::uint32_t> ds(k * kBlock), bw(k * kBlock);
  pairs([&](std::size_t begin, std::size_t count, const double* d) {
    const std::int8_t* label = labels.data() + begin;
    for (std::size_t m = 0; m < k; ++m) {
      count_block(a, m, label, count, d + m * count, ds.data() + m * count, bw.data() + m * count);
    }
#pragma omp parallel
    {
      CountSums different(k), similar(k), better(k);
#pragma omp for schedule(static)
      for (std::ptrdiff_t p = 0; p < static_cast<std::ptrdiff_t>(count); ++p) {
        const auto i = static_cast<std::size_t>(p);
        const bool dif = label[i] != 0;
        for (std::size_t x = 0; x < k; ++x) {
          for (std::size_t y = x + 1; y < k; ++y) {
            if (a.ds) {
              (dif ? different : similar).cross[x * k + y] +=
                  std::uint64_t(ds[x * count + i]) * ds[y * count + i];
            }
            if (dif)
              better.cross[x * k + y] += std::uint64_t(bw[x * count + i]) * bw[y * count + i];
          }
        }
      }
#pragma omp critical
      {
        a.ds_different.merge(different);
        a.ds_similar.merge(similar);
        a.bw.merge(better);
      }
    }
  });
}

// Sorts each metric's values (two passes over the pairs: counts, then the values).
void sort_values(Analysis& a, const std::vector<std::int8_t>& labels, const PairBlocks& pairs) {
  a.sorted.resize(a.k);
  std::vector<std::uint64_t> positive(a.k), negative(a.k);
  pairs([&](std::size_t begin, std::size_t count, const double* d) {
    for (std::size_t m = 0; m < a.k; ++m) {
      for (std::size_t i = 0; i < count; ++i) {
        const int l = labels[begin + i];
        const double b = l == 1 ? d[m * count + i] : -d[m * count + i];
        if (l == 0) continue;
        positive[m] += b > 0;
        negative[m] += b < 0;
      }
    }
  });
  for (std::size_t m = 0; m < a.k; ++m) {
    a.sorted[m].similar.reserve(a.similar);
    a.sorted[m].positive.reserve(positive[m]);
    a.sorted[m].negative.reserve(negative[m]);
  }
  pairs([&](std::size_t begin, std::size_t count, const double* d) {
    for (std::size_t m = 0; m < a.k; ++m) {
      SortedValues& s = a.sorted[m];
      for (std::size_t i = 0; i < count; ++i) {
        const int l = labels[begin + i];
        const double b = l == 1 ? d[m * count + i] : -d[m * count + i];
        if (l == 0) {
          s.similar.push_back(std::fabs(b));
        } else if (b > 0) {
          s.positive.push_back(b);
        } else if (b < 0) {
          s.negative.push_back(-b);
        } else {
          ++s.zeros;
        }
      }
    }
  });
  for (SortedValues& s : a.sorted) {
    for (std::vector<double>* v : {&s.similar, &s.positive, &s.negative}) {
      // In place (no copy of 8 bytes a pair); a multiset of doubles >= 0: one result.
      __gnu_parallel::sort(v->begin(), v->end(), __gnu_parallel::balanced_quicksort_tag());
    }
  }
}

// fastDeLong's AUC from the sum of the positives' ranks among all ratings (m positives, n
// negatives): sum tz = sum (twice the count against the negatives) / 2 + m (m + 1) / 2, an
// exact half-integer, so the same double as the ranks summed one by one.
double auc_of(std::uint64_t twice_counts, std::uint64_t m, double nd) {
  const double md = static_cast<double>(m);
  const double ranks = 0.5 * static_cast<double>(twice_counts + m * (m + 1));
  return ranks / md / nd - (md + 1.0) / 2.0 / nd;
}

// Krasula's analysis of the pairs `pairs` gives (labels valid, at least 2 different pairs).
KrasulaResult analyse(std::size_t k, const std::vector<std::int8_t>& labels,
                      const PairBlocks& pairs) {
  KrasulaResult r;
  for (const std::int8_t l : labels) {
    r.different += l != 0;
    r.better += l == 1;
    r.similar += l == 0;
  }
  require(r.different >= 2, "Krasula analysis: " + std::to_string(r.different) +
                                " significantly different pairs; at least 2 needed");
  require(labels.size() < kMaxPairs, "Krasula analysis: " + std::to_string(labels.size()) +
                                         " pairs; at most 2^31 - 1 are supported");
  Analysis a(k);
  a.different = r.different;
  a.similar = r.similar;
  a.ds = r.similar >= 2;
  sort_values(a, labels, pairs);
  a.ds_different.count = a.bw.count = r.different;
  a.ds_similar.count = r.similar;
  for (std::size_t m = 0; m < k; ++m) {
    const MetricSums s = sweep_sorted(a.sorted[m], a.ds);
    a.ds_different.sum[m] = s.ds_different;
    a.ds_different.cross[m * k + m] = s.ds_different_sq;
    a.ds_similar.sum[m] = s.ds_similar;
    a.ds_similar.cross[m * k + m] = s.ds_similar_sq;
    a.bw.sum[m] = s.bw;
    a.bw.cross[m * k + m] = s.bw_sq;
  }
  if (k >= 2) cross_pass(a, labels, pairs);
  const double md = static_cast<double>(r.different), nd = static_cast<double>(r.similar);
  r.cov_ds = std::vector<double>(k * k, kNaN);
  r.cov_bw.resize(k * k);
  for (std::size_t x = 0; x < k; ++x) {
    for (std::size_t y = x; y < k; ++y) {
      // fastDeLong's sx / m + sy / n; BW's v10 = 1 - (2 m - c) / (2 m) = v01, so sy = sx.
      const double bw = a.bw.covariance(x, y, md);
      r.cov_bw[x * k + y] = r.cov_bw[y * k + x] = bw / md + bw / md;
      if (!a.ds) continue;
      r.cov_ds[x * k + y] = r.cov_ds[y * k + x] =
          a.ds_different.covariance(x, y, nd) / md + a.ds_similar.covariance(x, y, md) / nd;
    }
  }
  std::vector<double> aucs_ds(k, kNaN), aucs_bw(k);
  for (std::size_t m = 0; m < k; ++m) {
    const SortedValues& s = a.sorted[m];
    if (a.ds)
      aucs_ds[m] = auc_of(static_cast<std::uint64_t>(a.ds_different.sum[m]), r.different, nd);
    aucs_bw[m] = auc_of(static_cast<std::uint64_t>(a.bw.sum[m]), r.different, md);
    KrasulaMetric km;
    km.auc_ds = aucs_ds[m];
    km.se_ds = std::sqrt(r.cov_ds[m * k + m]);
    km.auc_bw = aucs_bw[m];
    km.se_bw = std::sqrt(r.cov_bw[m * k + m]);
    // B > 0 and W = -B < 0: the pairs ordered right, counted in both lists.
    km.c0 = static_cast<double>(2 * s.positive.size()) / (2 * md);
    const std::vector<double>& sim = s.similar;
    km.thr_numpy = sim.empty() ? kNaN : percentile_numpy(sim, 0.95);
    km.thr_prctile = sim.empty() ? kNaN : percentile_prctile(sim, 0.95);
    r.metrics.push_back(km);
  }
  const double l = static_cast<double>(2 * r.different);
  for (std::size_t x = 0; x < k; ++x) {
    for (std::size_t y = x + 1; y < k; ++y) {
      KrasulaComparison c;
      c.a = x;
      c.b = y;
      c.cov_ds = r.cov_ds[x * k + y];
      c.cov_bw = r.cov_bw[x * k + y];
      c.z_delong_ds = a.ds ? delong_z(aucs_ds, r.cov_ds, k, x, y) : kNaN;
      c.p_delong_ds = a.ds ? two_sided_normal_p(c.z_delong_ds) : kNaN;
      c.z_delong_bw = delong_z(aucs_bw, r.cov_bw, k, x, y);
      c.p_delong_bw = two_sided_normal_p(c.z_delong_bw);
      const double c0a = r.metrics[x].c0, c0b = r.metrics[y].c0, pbar = (c0a + c0b) / 2.0;
      // Equal proportions (both 1, say, where the pooled variance is 0) are no evidence of a
      // difference: z = 0, p = 1 (VMAF's formula gives 0/0 there).
      c.z_c0 = c0a == c0b ? 0.0 : std::fabs(c0a - c0b) / std::sqrt(pbar * (1.0 - pbar) * 2.0 / l);
      c.p_c0 = two_sided_normal_p(c.z_c0);
      r.comparisons.push_back(c);
    }
  }
  return r;
}

std::vector<std::uint32_t> group_ids(const std::vector<std::string>& groups, std::size_t count) {
  require(groups.empty() || groups.size() == count, "pair labels: one group per stimulus needed");
  std::vector<std::uint32_t> ids(count, 0);
  std::map<std::string, std::uint32_t> id;
  for (std::size_t i = 0; i < groups.size(); ++i) {
    ids[i] = id.emplace(groups[i], static_cast<std::uint32_t>(id.size())).first->second;
  }
  return ids;
}

}  // namespace

// ---- PairLabels -------------------------------------------------------------------------------

void PairLabels::add(std::size_t a, std::size_t b, int l) {
  require(layout_ == Layout::kGiven, "PairLabels::add: the pairs are generated");
  require(a <= UINT32_MAX && b <= UINT32_MAX, "pair labels: a stimulus index above 2^32");
  first_.push_back(static_cast<std::uint32_t>(a));
  second_.push_back(static_cast<std::uint32_t>(b));
  label.push_back(static_cast<std::int8_t>(l));
}

PairLabels PairLabels::generated(Layout layout, const std::vector<std::uint32_t>& group_of) {
  require(layout != Layout::kGiven, "PairLabels::generated: a generated layout needed");
  require(group_of.size() <= UINT32_MAX, "pair labels: more than 2^32 stimuli");
  PairLabels p;
  p.layout_ = layout;
  p.group_of_ = group_of;
  const std::uint32_t groups =
      group_of.empty() ? 0 : *std::max_element(group_of.begin(), group_of.end()) + 1;
  p.member_start_.assign(groups + 1, 0);
  for (const std::uint32_t g : group_of) ++p.member_start_[g + 1];
  for (std::uint32_t g = 0; g < groups; ++g) p.member_start_[g + 1] += p.member_start_[g];
  std::vector<std::size_t> next(p.member_start_.begin(), p.member_start_.end() - 1);
  p.members_.resize(group_of.size());
  p.place_.resize(group_of.size());
  for (std::size_t i = 0; i < group_of.size(); ++i) {
    const std::size_t at = next[group_of[i]]++;
    p.members_[at] = static_cast<std::uint32_t>(i);
    p.place_[i] = static_cast<std::uint32_t>(at - p.member_start_[group_of[i]]);
  }
  p.row_start_.assign(group_of.size() + 1, 0);
  for (std::size_t row = 0; row < group_of.size(); ++row) {
    p.row_start_[row + 1] = p.row_start_[row] + p.partners(row);
  }
  return p;
}

std::size_t PairLabels::partners(std::size_t row) const {
  if (layout_ == Layout::kLowerTriangle) return place_[row];
  const std::uint32_t g = group_of_[row];
  return member_start_[g + 1] - member_start_[g];
}

std::size_t PairLabels::pair_count() const {
  return layout_ == Layout::kGiven ? first_.size() : row_start_.back();
}

std::size_t PairLabels::first(std::size_t p) const {
  if (layout_ == Layout::kGiven) return first_.at(p);
  require(p < pair_count(), "PairLabels: no pair " + std::to_string(p));
  return static_cast<std::size_t>(std::upper_bound(row_start_.begin(), row_start_.end(), p) -
                                  row_start_.begin()) -
         1;
}

std::size_t PairLabels::second(std::size_t p) const {
  if (layout_ == Layout::kGiven) return second_.at(p);
  const std::size_t row = first(p);
  return members_[member_start_[group_of_[row]] + (p - row_start_[row])];
}

std::size_t PairLabels::stimuli_named() const {
  if (layout_ != Layout::kGiven) return pair_count() == 0 ? 0 : group_of_.size();
  std::size_t n = 0;
  for (std::size_t p = 0; p < first_.size(); ++p) {
    n = std::max<std::size_t>(n, std::max(first_[p], second_[p]) + std::size_t(1));
  }
  return n;
}

// ---- labels -----------------------------------------------------------------------------------

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
    require(n[i] >= 2,
            "pair labels: stimulus " + std::to_string(i + 1) + " has fewer than 2 observers (n)");
  }
  PairLabels pairs =
      PairLabels::generated(PairLabels::Layout::kLowerTriangle, group_ids(groups, count));
  pairs.rule =
      "one-sided 95 % z test of the MOS difference, SE = sqrt(SD1^2/n1 + SD2^2/n2) "
      "(Krasula; ITU-T J.149)";
  pairs.label.reserve(pairs.pair_count());
  pairs.for_each([&](std::size_t j, std::size_t i) {
    double se = std::sqrt(sd[j] * sd[j] / n[j] + sd[i] * sd[i] / n[i]);
    if (se == 0) se = 1e-6;
    const double diff = mos[j] - mos[i];
    const double z = diff / se;
    // The test's own formula decides only near its threshold (|z| = 1.6449): elsewhere it is
    // far from 0.95 (0.9452 at 1.6, 0.9554 at 1.7) and erf's rounding cannot change it.
    const double az = std::fabs(z);
    const bool significant = az > kSurelySignificant ||
                             (az >= kSurelyNot && 0.5 + std::erf(az / std::sqrt(2.0)) / 2 >= 0.95);
    pairs.label.push_back(static_cast<std::int8_t>(significant ? (diff > 0) - (diff < 0) : 0));
  });
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
      require(std::isfinite(x),
              "pair labels: stimulus " + std::to_string(i + 1) + " has a non-finite score");
      sum.add(x);
    }
    const double len = static_cast<double>(s.size());
    mean[i] = sum.value() / len;
    Sum squares;
    for (double x : s) squares.add((x - mean[i]) * (x - mean[i]));
    var_over_n[i] = squares.value() / (len - 1) / len;
  }
  PairLabels pairs =
      PairLabels::generated(PairLabels::Layout::kAllOrdered, group_ids(groups, count));
  pairs.rule =
      "two-sided z test |z| > 2 of the mean difference, var with N-1, every ordered "
      "pair and self-pair (VMAF AucPerfMetric)";
  pairs.label.reserve(pairs.pair_count());
  pairs.for_each([&](std::size_t i, std::size_t j) {
    double den = var_over_n[i] + var_over_n[j];
    if (den == 0) den = 1e-8;
    const double z = (mean[i] - mean[j]) / std::sqrt(den);
    pairs.label.push_back(static_cast<std::int8_t>(z > 2 ? 1 : z < -2 ? -1 : 0));
  });
  return pairs;
}

// ---- the analysis -----------------------------------------------------------------------------

KrasulaResult krasula_analysis(const std::vector<std::vector<double>>& differences,
                               const std::vector<int>& labels) {
  const std::size_t k = differences.size(), count = labels.size();
  require(k >= 1, "Krasula analysis: no metric");
  for (const auto& d : differences) {
    require(d.size() == count,
            "Krasula analysis: a metric's differences and the labels differ "
            "in length");
    for (double x : d) require(std::isfinite(x), "Krasula analysis: a non-finite difference");
  }
  std::vector<std::int8_t> small(count);
  for (std::size_t p = 0; p < count; ++p) {
    require(labels[p] == -1 || labels[p] == 0 || labels[p] == 1,
            "Krasula analysis: a label other than -1, 0, 1");
    small[p] = static_cast<std::int8_t>(labels[p]);
  }
  const PairBlocks blocks = [&](const BlockFn& fn) {
    std::vector<double> d(k * kBlock);
    for (std::size_t begin = 0; begin < count; begin += kBlock) {
      const std::size_t n = std::min(kBlock, count - begin);
      for (std::size_t m = 0; m < k; ++m) {
        std::copy_n(differences[m].begin() + static_cast<std::ptrdiff_t>(begin), n,
                    d.begin() + m * n);
      }
      fn(begin, n, d.data());
    }
  };
  return analyse(k, small, blocks);
}

KrasulaResult krasula_analysis(const std::vector<std::vector<double>>& scores,
                               const PairLabels& pairs) {
  const std::size_t k = scores.size();
  require(k >= 1, "Krasula analysis: no metric");
  require(pairs.pair_count() == pairs.size(), "Krasula analysis: pairs without their labels");
  const std::size_t named = pairs.stimuli_named();
  for (const auto& s : scores) {
    require(named <= s.size(), "Krasula analysis: a pair names a stimulus the scores do not have");
  }
  for (const std::int8_t l : pairs.label) {
    require(l == -1 || l == 0 || l == 1, "Krasula analysis: a label other than -1, 0, 1");
  }
  const PairBlocks blocks = [&](const BlockFn& fn) {
    std::vector<std::size_t> first(kBlock), second(kBlock);
    std::vector<double> d(k * kBlock);
    std::size_t begin = 0, n = 0;
    const auto flush = [&] {
      for (std::size_t m = 0; m < k; ++m) {
        const double* s = scores[m].data();
        for (std::size_t i = 0; i < n; ++i) {
          const double x = s[first[i]] - s[second[i]];
          if (!std::isfinite(x)) require(false, "Krasula analysis: a non-finite difference");
          d[m * n + i] = x;
        }
      }
      fn(begin, n, d.data());
      begin += n;
      n = 0;
    };
    pairs.for_each([&](std::size_t a, std::size_t b) {
      first[n] = a;
      second[n] = b;
      if (++n == kBlock) flush();
    });
    if (n > 0) flush();
  };
  return analyse(k, pairs.label, blocks);
}

}  // namespace qm3d::evaluation
