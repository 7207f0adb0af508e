#include "qm3d/evaluation/krasula.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <numeric>
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
template <class Sorted>
double percentile_numpy(const Sorted& x, double p) {  // x sorted
  const double h = (static_cast<double>(x.size()) - 1) * p;
  const std::size_t lo = static_cast<std::size_t>(std::floor(h));
  if (lo + 1 >= x.size()) return x[x.size() - 1];
  const double t = h - static_cast<double>(lo), a = x[lo], b = x[lo + 1], diff = b - a;
  return t >= 0.5 ? b - diff * (1 - t) : a + diff * t;
}

// MATLAB's / Octave's prctile (Hazen): x_(k) at p = (k - 0.5) / n, linear between, the extremes
// beyond.
template <class Sorted>
double percentile_prctile(const Sorted& x, double p) {  // x sorted
  const double n = static_cast<double>(x.size());
  const double pos = n * p + 0.5;  // 1-based
  if (pos <= 1) return x[0];
  if (pos >= n) return x[x.size() - 1];
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

// Bucket keys for values in [0, range]: floor(x * buckets / range), clamped to the last
// bucket. The key never decreases as x grows (a product by a constant >= 0 and a truncation,
// both monotone), so every value in a lower bucket is below x and every one in a higher bucket
// above it: a count at x needs only x's own bucket.
class BucketKey {
 public:
  BucketKey() = default;
  // A subnormal range would make the scale infinite (and 0 * inf NaN): it stays finite.
  BucketKey(double range, std::size_t buckets)
      : scale_(range > 0 ? std::min(static_cast<double>(buckets) / range,
                                    std::numeric_limits<double>::max())
                         : 0),
        last_(buckets - 1) {}
  std::size_t operator()(double x) const {
    const double key = x * scale_;
    return key < static_cast<double>(last_) ? static_cast<std::size_t>(key) : last_;
  }

 private:
  double scale_ = 0;
  std::size_t last_ = 0;
};

// Pairs of stimuli whose indices fit 16 bits each are stored as one 32-bit token (a, b) with
// s[a] - s[b] >= 0, their value recomputed from the scores when read (x - y = -(y - x) exactly,
// so it is |d| bit for bit): half the memory of a double a pair (10,000 stimuli: 50 M pairs).
constexpr std::size_t kPackedStimuli = std::size_t(1) << 16;

std::uint32_t pair_token(std::uint32_t a, std::uint32_t b, double d) {
  return d >= 0 ? a << 16 | b : b << 16 | a;
}

// A sorted array of values >= 0 (stored, or pair tokens) with a bucket index (about 16 values a
// bucket), so that a count at any x reads one index entry and x's bucket: a few cache lines,
// where a binary search of a 25 M array reads ~25.
class IndexedValues {
 public:
  // n values, as tokens of pairs of `scores` when it is given, else stored.
  void allocate(std::size_t n, const double* scores) {
    scores_ = scores;
    // Plain pages: huge ones (madvise) cost more in the kernel's compaction than they saved.
    if (scores_ != nullptr)
      tokens_.resize(n);
    else
      values_.resize(n);
  }
  void put(std::size_t at, double value, std::uint32_t token) {
    if (scores_ != nullptr)
      tokens_[at] = token;
    else
      values_[at] = value;
  }
  std::size_t size() const { return scores_ != nullptr ? tokens_.size() : values_.size(); }
  double operator[](std::size_t i) const {
    if (scores_ == nullptr) return values_[i];
    const std::uint32_t t = tokens_[i];
    return scores_[t >> 16] - scores_[t & 0xFFFF];
  }
  std::uint32_t token(std::size_t i) const { return tokens_[i]; }
  const void* address(std::size_t i) const {
    return scores_ != nullptr ? static_cast<const void*>(tokens_.data() + i)
                              : static_cast<const void*>(values_.data() + i);
  }
  // Sorts [lo, hi) (a multiset of doubles has one sorted order; tokens of equal values are
  // ordered by token), with `scratch` for the tokens' values.
  void sort(std::size_t lo, std::size_t hi,
            std::vector<std::pair<double, std::uint32_t>>& scratch) {
    const auto at = [](auto& v, std::size_t i) {
      return v.begin() + static_cast<std::ptrdiff_t>(i);
    };
    if (scores_ == nullptr) {
      std::sort(at(values_, lo), at(values_, hi));
      return;
    }
    scratch.clear();
    for (std::size_t i = lo; i < hi; ++i) scratch.emplace_back((*this)[i], tokens_[i]);
    std::sort(scratch.begin(), scratch.end());
    for (std::size_t i = lo; i < hi; ++i) tokens_[i] = scratch[i - lo].second;
  }
  // The first index in [lo, hi) whose value fails `before` (which holds for a prefix).
  template <class Before>
  std::size_t partition_point(std::size_t lo, std::size_t hi, Before before) const {
    while (lo < hi) {
      const std::size_t mid = lo + (hi - lo) / 2;
      if (before((*this)[mid]))
        lo = mid + 1;
      else
        hi = mid;
    }
    return lo;
  }
  // Builds the index of the sorted values (one pass).
  void index(double range) {
    const std::size_t n = size(), buckets = std::max<std::size_t>(1, n / 16);
    key = BucketKey(range, buckets);
    start.assign(buckets + 1, static_cast<std::uint32_t>(n));
    std::size_t next = 0;
    for (std::size_t i = 0; i < n; ++i) {
      for (const std::size_t b = key((*this)[i]); next <= b; ++next) {
        start[next] = static_cast<std::uint32_t>(i);
      }
    }
  }
  // {#{values < x}, #{values == x}}, at any x.
  std::pair<std::uint64_t, std::uint64_t> below_and_equal(double x) const {
    const std::size_t b = key(x);
    const std::size_t lo = start[b], hi = start[b + 1];
    if (lo == hi) return {lo, 0};
    const double first = (*this)[lo], last = (*this)[hi - 1];
    if (x < first) return {lo, 0};
    if (x > last) return {hi, 0};
    if (first == last) return {lo, hi - lo};  // one distinct value, and x is it
    const std::size_t l = partition_point(lo, hi, [x](double v) { return v < x; });
    const std::size_t u = partition_point(l, hi, [x](double v) { return v <= x; });
    return {l, u - l};
  }

  BucketKey key;
  std::vector<std::uint32_t> start;  // bucket b: [start[b], start[b + 1]); below kMaxPairs

 private:
  const double* scores_ = nullptr;
  std::vector<double> values_;
  std::vector<std::uint32_t> tokens_;
};

// Counting in a sorted array at ascending query values: each search starts where the last one
// ended and gallops forward (exponential, then binary search), so that queries in ascending
// order (the sums over one metric's own sorted values) sweep the array once.
class Sweep {
 public:
  explicit Sweep(const IndexedValues& sorted) : v_(sorted) {}
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
    return v_.partition_point(lo, std::min(hi, v_.size()), before);
  }
  const IndexedValues& v_;
  std::size_t at_ = 0;
};

// How a count at arbitrary x reaches the index: kCount counts; the other two only touch what the
// count will read, so that the cross pass can run a chunk of pairs three times: touching the
// index entries, then the buckets' values (both fetched together, not one miss after the
// other), then counting in the cache.
enum class Reach { kCount, kTouchIndex, kTouchValues };

template <Reach kReach>
class Probe {
 public:
  explicit Probe(const IndexedValues& values) : v_(values) {}
  std::pair<std::uint64_t, std::uint64_t> below_and_equal(double x) const {
    if constexpr (kReach == Reach::kCount) {
      return v_.below_and_equal(x);
    } else {
      const std::size_t b = v_.key(x);
      if constexpr (kReach == Reach::kTouchIndex) {
        __builtin_prefetch(v_.start.data() + b);
      } else if (const std::size_t lo = v_.start[b], hi = v_.start[b + 1]; lo < hi) {
        __builtin_prefetch(v_.address(lo));
        __builtin_prefetch(v_.address(hi - 1));
      }
      return {0, 0};
    }
  }

 private:
  const IndexedValues& v_;
};

// One metric's values, sorted: |d| of the similar pairs (S), and B (d of the pairs labelled 1,
// -d of those labelled -1) split by sign, so that the different pairs' |d| (D = |B|) and B
// itself are both counted in the same two arrays.
struct SortedValues {
  IndexedValues similar;    // S, ascending
  IndexedValues positive;   // B > 0, ascending
  IndexedValues negative;   // -B for B < 0, ascending
  std::uint64_t zeros = 0;  // B == 0
  // With tokens, the B == 0 pairs' tokens oriented by their label (B of another metric is
  // s[a] - s[b]); kept for the first metric only (the cross sweep).
  std::vector<std::uint32_t> zero_tokens;
};

// The structural-component counts of one metric's pairs, at their |d| in ascending order (a
// sweep of each array). Twice the Mann-Whitney counts (ties half), exact integers:
// DS, a different pair's |d| = x against S: 2 #{S < x} + #{S == x};
// DS, a similar pair's |d| = y against D = |B|: 2 #{D < y} + #{D == y};
// BW, a B value b against W = -B: 2 #{W < b} + #{W == b} = 2 #{B > -b} + #{B == -b}.
template <class Search>
class Counts {
 public:
  explicit Counts(const SortedValues& s)
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
  Search similar_, positive_, negative_;
};
using Counter = Counts<Sweep>;                // queries in ascending order
using Lookup = Counts<Probe<Reach::kCount>>;  // queries in any order

// Pairs in blocks: fn(begin, count, d, first, second) with d[m * count + i] metric m's
// difference s_m[first[i]] - s_m[second[i]] of pair begin + i, for consecutive blocks in pair
// order; first and second are null unless the pairs' stimuli (and the scores) are known and
// fewer than kPackedStimuli.
using BlockFn = std::function<void(std::size_t begin, std::size_t count, const double* d,
                                   const std::uint32_t* first, const std::uint32_t* second)>;
using PairBlocks = std::function<void(const BlockFn&)>;
// Pairs generated at a time: a few MB of differences.
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
  Distinct(const IndexedValues& a, const IndexedValues* b, std::uint64_t zeros)
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
  static inline const IndexedValues empty_{};
  const IndexedValues& a_;
  const IndexedValues& b_;
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
  std::vector<const double*> scores;  // with pair tokens: each metric's scores
  // The three lists' sums: DS's different pairs, its similar pairs, BW's B values.
  CountSums ds_different, ds_similar, bw;
  explicit Analysis(std::size_t metrics)
      : k(metrics), ds_different(metrics), ds_similar(metrics), bw(metrics) {}
};

// The cross sums sum c_a c_b (a < b) of the three lists, pair by pair (needed with 2 metrics or
// more), each pair's counts looked up in each metric's indexed arrays: exact integer sums, so
// the pairs are split between threads and summed in any order.
void cross_pass(Analysis& a, const std::vector<std::int8_t>& labels, const PairBlocks& pairs) {
  const std::size_t k = a.k;
  // Pairs per chunk: enough lookups in flight to hide the memory's latency, few enough that
  // what they touch stays in L1.
  constexpr std::size_t kChunk = 16;
  pairs([&](std::size_t begin, std::size_t count, const double* d, const std::uint32_t*,
            const std::uint32_t*) {
    const std::int8_t* label = labels.data() + begin;
    // Every count of pair i under each metric, through the Search kind of counts (c[m]).
    const auto counts = [&](auto& c, std::size_t i, std::uint64_t* ds, std::uint64_t* bw) {
      const int l = label[i];
      for (std::size_t m = 0; m < k; ++m) {
        const double x = d[m * count + i];
        if (a.ds) ds[m] = l != 0 ? c[m].ds_different(std::fabs(x)) : c[m].ds_similar(std::fabs(x));
        if (l != 0) bw[m] = c[m].bw(l == 1 ? x : -x);
      }
    };
    const std::size_t chunks = (count + kChunk - 1) / kChunk;
#pragma omp parallel
    {
      CountSums different(k), similar(k), better(k);
      std::vector<Counts<Probe<Reach::kTouchIndex>>> index(a.sorted.begin(), a.sorted.end());
      std::vector<Counts<Probe<Reach::kTouchValues>>> values(a.sorted.begin(), a.sorted.end());
      std::vector<Lookup> lookups(a.sorted.begin(), a.sorted.end());
      std::vector<std::uint64_t> ds(k), bw(k);  // counts below 2^32 (kMaxPairs)
      // This thread's chunks [c0, c1), pipelined: chunk c's index entries are touched two steps
      // before it is counted, its values one step before.
      const auto threads = static_cast<std::size_t>(omp_get_num_threads());
      const auto thread = static_cast<std::size_t>(omp_get_thread_num());
      const std::size_t c0 = chunks * thread / threads, c1 = chunks * (thread + 1) / threads;
      const auto each = [&](std::size_t c, const auto& fn) {
        for (std::size_t i = c * kChunk; i < std::min(count, (c + 1) * kChunk); ++i) fn(i);
      };
      for (std::size_t c = c0; c < c1 + 2; ++c) {
        if (c < c1) each(c, [&](std::size_t i) { counts(index, i, ds.data(), bw.data()); });
        if (c >= c0 + 1 && c - 1 < c1) {
          each(c - 1, [&](std::size_t i) { counts(values, i, ds.data(), bw.data()); });
        }
        if (c < c0 + 2) continue;
        each(c - 2, [&](std::size_t i) {
          counts(lookups, i, ds.data(), bw.data());
          const bool dif = label[i] != 0;
          for (std::size_t x = 0; x < k; ++x) {
            for (std::size_t y = x + 1; y < k; ++y) {
              if (a.ds) (dif ? different : similar).cross[x * k + y] += ds[x] * ds[y];
              if (dif) better.cross[x * k + y] += bw[x] * bw[y];
            }
          }
        });
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

// The cross sums with pair tokens: the first metric's sorted arrays (and its B == 0 tokens) name
// every pair once, with its label's class, so they are read in order (the first metric's counts
// from sweeps) and only the other metrics' counts are looked up, at B = +-(s[a] - s[b]): a
// token (a, b) in the positive array has l d = s[a] - s[b] under every metric (d's orientation
// and l's cancel), in the negative array s[b] - s[a]. Exact integer sums: any split of threads.
void cross_sweep(Analysis& a) {
  const std::size_t k = a.k;
  const SortedValues& first = a.sorted[0];
  // list 0: S (similar pairs); 1: B > 0; 2: B < 0 (both different pairs); 3: B == 0.
  for (int list = a.ds ? 0 : 1; list < 4; ++list) {
    const IndexedValues* values = list == 0   ? &first.similar
                                  : list == 1 ? &first.positive
                                              : &first.negative;
    const std::size_t n = list == 3 ? first.zero_tokens.size() : values->size();
#pragma omp parallel
    {
      CountSums different(k), similar(k), better(k);
      Counter sweep(first);  // ascending x in this thread's share
      std::vector<Lookup> lookups(a.sorted.begin(), a.sorted.end());
      std::vector<std::uint64_t> ds(k), bw(k);  // counts below 2^32 (kMaxPairs)
#pragma omp for schedule(static)
      for (std::ptrdiff_t p = 0; p < static_cast<std::ptrdiff_t>(n); ++p) {
        const auto i = static_cast<std::size_t>(p);
        const std::uint32_t t = list == 3 ? first.zero_tokens[i] : values->token(i);
        const std::size_t sa = t >> 16, sb = t & 0xFFFF;
        const double x = list == 3 ? 0.0 : (*values)[i];
        if (list == 0) {
          ds[0] = sweep.ds_similar(x);
          for (std::size_t m = 1; m < k; ++m) {
            ds[m] = lookups[m].ds_similar(std::fabs(a.scores[m][sa] - a.scores[m][sb]));
          }
        } else {
          if (a.ds) ds[0] = sweep.ds_different(x);
          bw[0] = sweep.bw(list == 2 ? -x : x);
          for (std::size_t m = 1; m < k; ++m) {
            const double b =
                list == 2 ? a.scores[m][sb] - a.scores[m][sa] : a.scores[m][sa] - a.scores[m][sb];
            if (a.ds) ds[m] = lookups[m].ds_different(std::fabs(b));
            bw[m] = lookups[m].bw(b);
          }
        }
        for (std::size_t u = 0; u < k; ++u) {
          for (std::size_t v = u + 1; v < k; ++v) {
            if (list == 0) similar.cross[u * k + v] += ds[u] * ds[v];
            if (list != 0 && a.ds) different.cross[u * k + v] += ds[u] * ds[v];
            if (list != 0) better.cross[u * k + v] += bw[u] * bw[v];
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
  }
}

// The array (0 S, 1 B > 0, 2 -B for B < 0; 3 B == 0, no array) a pair labelled l with
// difference d goes to, and its value there.
int place(int l, double d, double& value) {
  const double b = l == 1 ? d : -d;
  value = std::fabs(d);
  return l == 0 ? 0 : b > 0 ? 1 : b < 0 ? 2 : 3;
}

// Sorts each bucket [bucket[b], bucket[b + 1]) of `v` (in parallel: a multiset of doubles has
// one sorted order, so the same array on any number of threads), then indexes it.
void sort_buckets(IndexedValues& v, const std::vector<std::size_t>& bucket, double range) {
  const auto buckets = static_cast<std::ptrdiff_t>(bucket.size() - 1);
#pragma omp parallel
  {
    std::vector<std::pair<double, std::uint32_t>> scratch;
#pragma omp for schedule(dynamic, 16)
    for (std::ptrdiff_t b = 0; b < buckets; ++b) {
      const auto i = static_cast<std::size_t>(b);
      v.sort(bucket[i], bucket[i + 1], scratch);
    }
  }
  v.index(range);
}

// Sorts each metric's values by buckets: one pass over the pairs for the arrays' sizes and
// ranges, one to count each coarse bucket's values, one to place them in their buckets; then
// the buckets are sorted and indexed. With `scores` (one per metric; the blocks then
// name the pairs' stimuli), the arrays hold pair tokens.
void sort_values(Analysis& a, const std::vector<std::int8_t>& labels, const PairBlocks& pairs,
                 const std::vector<const double*>& scores) {
  const std::size_t k = a.k;
  a.sorted.resize(k);
  a.scores = scores;
  const auto arrays = [&a](std::size_t m) {
    SortedValues& s = a.sorted[m];
    return std::array<IndexedValues*, 3>{&s.similar, &s.positive, &s.negative};
  };
  std::vector<std::array<std::size_t, 4>> sizes(k, {0, 0, 0, 0});
  std::vector<std::array<double, 3>> ranges(k, {0, 0, 0});
  const auto each_value = [&](const auto& fn) {
    pairs([&](std::size_t begin, std::size_t count, const double* d, const std::uint32_t* first,
              const std::uint32_t* second) {
      for (std::size_t m = 0; m < k; ++m) {
        for (std::size_t i = 0; i < count; ++i) {
          double v = 0;
          const double dm = d[m * count + i];
          const int l = labels[begin + i], w = place(l, dm, v);
          // B == 0 (w 3): oriented by the label, so that B = s[a] - s[b] under every metric.
          fn(m, w, v, first == nullptr ? 0 : pair_token(first[i], second[i], w == 3 ? l : dm));
        }
      }
    });
  };
  each_value([&](std::size_t m, int w, double v, std::uint32_t) {
    ++sizes[m][w];
    if (w < 3) ranges[m][w] = std::max(ranges[m][w], v);
  });
  // Coarse buckets of ~256 values (each sorted in the core's L1 cache).
  std::vector<std::array<BucketKey, 3>> keys(k);
  std::vector<std::array<std::vector<std::size_t>, 3>> at(k);  // each bucket's next slot
  for (std::size_t m = 0; m < k; ++m) {
    a.sorted[m].zeros = sizes[m][3];
    for (int w = 0; w < 3; ++w) {
      const std::size_t buckets = std::clamp<std::size_t>(sizes[m][w] >> 8, 1, 1 << 18);
      keys[m][w] = BucketKey(ranges[m][w], buckets);
      at[m][w].assign(buckets + 1, 0);
      arrays(m)[w]->allocate(sizes[m][w], scores.empty() ? nullptr : scores[m]);
    }
  }
  each_value([&](std::size_t m, int w, double v, std::uint32_t) {
    if (w < 3) ++at[m][w][keys[m][w](v) + 1];
  });
  for (auto& per_metric : at) {
    for (std::vector<std::size_t>& c : per_metric) std::partial_sum(c.begin(), c.end(), c.begin());
  }
  std::vector<std::array<std::vector<std::size_t>, 3>> next = at;
  if (!scores.empty()) a.sorted[0].zero_tokens.reserve(sizes[0][3]);
  each_value([&](std::size_t m, int w, double v, std::uint32_t token) {
    if (w < 3)
      arrays(m)[w]->put(next[m][w][keys[m][w](v)]++, v, token);
    else if (m == 0 && !scores.empty())
      a.sorted[0].zero_tokens.push_back(token);
  });
  for (std::size_t m = 0; m < k; ++m) {
    for (int w = 0; w < 3; ++w) {
      sort_buckets(*arrays(m)[w], at[m][w], ranges[m][w]);
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
                      const PairBlocks& pairs, const std::vector<const double*>& scores) {
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
  sort_values(a, labels, pairs, scores);
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
  if (k >= 2 && !a.scores.empty()) cross_sweep(a);
  if (k >= 2 && a.scores.empty()) cross_pass(a, labels, pairs);
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
    const IndexedValues& sim = s.similar;
    km.thr_numpy = sim.size() == 0 ? kNaN : percentile_numpy(sim, 0.95);
    km.thr_prctile = sim.size() == 0 ? kNaN : percentile_prctile(sim, 0.95);
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
      fn(begin, n, d.data(), nullptr, nullptr);
    }
  };
  return analyse(k, small, blocks, {});
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
  // Pairs of fewer than kPackedStimuli stimuli are stored as tokens (the blocks name them).
  const bool packed = named <= kPackedStimuli;
  std::vector<const double*> packed_scores;
  for (const auto& s : scores) {
    if (packed) packed_scores.push_back(s.data());
  }
  const PairBlocks blocks = [&](const BlockFn& fn) {
    std::vector<std::uint32_t> first(kBlock), second(kBlock);
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
      fn(begin, n, d.data(), packed ? first.data() : nullptr, packed ? second.data() : nullptr);
      begin += n;
      n = 0;
    };
    pairs.for_each([&](std::size_t a, std::size_t b) {
      first[n] = static_cast<std::uint32_t>(a);  // below 2^32 (PairLabels)
      second[n] = static_cast<std::uint32_t>(b);
      if (++n == kBlock) flush();
    });
    if (n > 0) flush();
  };
  return analyse(k, pairs.label, blocks, packed_scores);
}

}  // namespace qm3d::evaluation
