#include "psnr_search.h"

#include <algorithm>
#include <cmath>

namespace qm3d::pointcloud::detail {

namespace {

/// Average points per column (the column width is set from the box's extents across the columns
/// as if the cloud were a surface across them: MPEG clouds are surfaces). 8 was the fastest of
/// 2, 4, 8, 16, 32 on the 1M-point sphere pair of bench/run_benchmarks.sh psnr.
constexpr double kPointsPerColumn = 8;
/// Rings of columns searched around the query's before the tree answers.
constexpr long kMaxRings = 16;
/// A query farther than this many column widths from the grid's origin: the tree answers. Below
/// it, cell()'s rounding is under 1e6 x 2^-52 column widths, so kSlack covers it.
constexpr double kFar = 1e6;
constexpr double kSlack = 1e-8;
/// Relative amount by which nanoflann's distance can be below the exact one (float differences:
/// 2^-22) plus the rounding of the lower bounds here, with a wide margin.
constexpr double kShrink = 1e-6;
/// Relative rounding allowed for nanoflann's branch bounds (sums and differences of squared
/// distances to the cut planes, in double: below 1e-13 at any depth) and for exact_distance2.
constexpr double kBoundRounding = 1e-10;
/// Columns up to this size are scanned whole (cheaper than a binary search).
constexpr long kLinearScan = 16;
/// Sampled queries that decide whether the grid is used, and the share of them the grid may
/// leave to the tree (above it, e.g. on voxelised clouds, the tree alone answers: building it
/// then costs no more than before, and the grid is freed).
constexpr std::size_t kSampleQueries = 512;
constexpr double kMaxTreeShare = 0.05;
/// The tie run a sampled query with tied neighbours needs (the colour pass's first query).
constexpr std::size_t kSampleRun = 10;

/// nanoflann's L2_Adaptor<float, ..., double>: float differences, squared and summed in double in
/// x, y, z order (this file is built without fused multiply-adds).
double column_distance2(const Point3f& q, const Point3f& p) {
  const double d0 = q[0] - p[0];
  const double d1 = q[1] - p[1];
  const double d2 = q[2] - p[2];
  double r = 0.0;
  r += d0 * d0;
  r += d1 * d1;
  r += d2 * d2;
  return r;
}

/// The squared distance of two float points in double (each difference, square and sum rounded
/// to double: 1e-15 relative): the distance nanoflann's branch bounds approximate.
double exact_distance2(const Point3f& q, const Point3f& p) {
  const double d0 = double(q[0]) - double(p[0]);
  const double d1 = double(q[1]) - double(p[1]);
  const double d2 = double(q[2]) - double(p[2]);
  return d0 * d0 + d1 * d1 + d2 * d2;
}

}  // namespace

/// The k + 1 smallest distances seen, ascending (a later equal distance after the earlier one);
/// `worst`: the largest while full, else infinity.
struct PointColumns::Best {
  std::size_t capacity = 0;
  std::size_t count = 0;
  double worst = HUGE_VAL;
  double d[kMaxNeighbours + 1];
  const Entry* e[kMaxNeighbours + 1];

  void add(double dist, const Entry* entry) {
    if (!(dist < worst)) return;
    std::size_t j = count < capacity ? count++ : capacity - 1;
    for (; j > 0 && d[j - 1] > dist; --j) {
      d[j] = d[j - 1];
      e[j] = e[j - 1];
    }
    d[j] = dist;
    e[j] = entry;
    if (count == capacity) worst = d[capacity - 1];
  }

  // Whether every point at exact squared distance e2 or more is farther, as nanoflann computes
  // distances (its float differences shrink them by at most 2^-22 relative), than the worst.
  bool beyond(double e2) const { return e2 * (1 - kShrink) > worst; }
};

inline double PointColumns::cell(double x, int axis) const { return (x - origin_[axis]) / h_; }

// The gap, in column widths, between a query at `u` and column `i` along one axis (0 in it),
// less the rounding of cell() (below kSlack for |u| < kFar).
inline double PointColumns::gap_to(double u, long i) {
  const double gap = u < i ? i - u : u - (i + 1);
  return std::max(0.0, gap - kSlack);
}

PointColumns::PointColumns(const std::vector<Point3f>& points) {
  const std::size_t n = points.size();
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k) lo[k] = hi[k] = n ? points[0][k] : 0.0;
  for (const Point3f& p : points) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min<double>(lo[k], p[k]);
      hi[k] = std::max<double>(hi[k], p[k]);
    }
  }
  // Columns across x (the queries come sorted by x, pc_error's order: consecutive queries then
  // search the same few rows of columns) and the longer of y and z; sorted along the other.
  if (hi[2] - lo[2] > hi[1] - lo[1]) std::swap(axis_[1], axis_[2]);
  const double ea = hi[axis_[0]] - lo[axis_[0]];
  const double eb = hi[axis_[1]] - lo[axis_[1]];
  const double columns = std::max(1.0, static_cast<double>(n) / kPointsPerColumn);
  // At least max(ea, eb) / columns: at most 3 x columns + 1 of them for any extents.
  h_ = std::max(std::sqrt(ea * eb / columns), std::max(ea, eb) / columns);
  if (!(h_ > 0)) h_ = 1.0;
  origin_[0] = lo[axis_[0]];
  origin_[1] = lo[axis_[1]];
  // cell() is monotone and gives the box's maximum its largest value: every point has a column.
  ga_ = static_cast<long>(std::floor(cell(hi[axis_[0]], 0))) + 1;
  gb_ = static_cast<long>(std::floor(cell(hi[axis_[1]], 1))) + 1;
  std::vector<std::uint32_t> column(n);
  start_.assign(static_cast<std::size_t>(ga_ * gb_) + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const long c = static_cast<long>(std::floor(cell(points[i][axis_[0]], 0))) * gb_ +
                   static_cast<long>(std::floor(cell(points[i][axis_[1]], 1)));
    column[i] = static_cast<std::uint32_t>(c);
    ++start_[c + 1];
  }
  for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
  entries_.resize(n);
  std::vector<std::uint32_t> next(start_.begin(), start_.end() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    entries_[next[column[i]]++] = {points[i], static_cast<std::uint32_t>(i)};
  }
  const int c = axis_[2];
  for (std::size_t k = 0; k + 1 < start_.size(); ++k) {
    std::sort(entries_.begin() + start_[k], entries_.begin() + start_[k + 1],
              [c](const Entry& x, const Entry& y) { return x.p[c] < y.p[c]; });
  }
}

// The exactness condition of psnr_search.h for the k + 1 nearest in `best`: distances strictly
// increasing (no traversal order decides), and each of the first k exactly nearer than the
// (k+1)-th distance by more than the rounding of nanoflann's branch bounds. A point the tree
// skips has a bound above the k-th distance it returns, which would then be at least best.d[k],
// and the bound is at most the point's exact distance (accurate to 1e-13 relative): so none of
// the first k can be skipped.
bool PointColumns::settled_by_distance(const Point3f& q, const Best& best, std::size_t k) {
  for (std::size_t j = 0; j < k; ++j) {
    if (!(best.d[j] < best.d[j + 1])) return false;
    if (!(exact_distance2(q, best.e[j]->p) * (1 + kBoundRounding) < best.d[k])) return false;
  }
  return true;
}

// Adds the points of column `col` that may be nearer than best's worst: scanned outwards from
// the query along the sorted axis, each way until the gap along that axis alone is farther.
void PointColumns::scan_column(const Point3f& q, std::size_t col, Best& best) const {
  const int c = axis_[2];
  const double qc = q[c];
  const auto first = entries_.begin() + start_[col];
  const auto last = entries_.begin() + start_[col + 1];
  if (last - first <= kLinearScan) {  // ascending: skip those below, stop above
    for (auto it = first; it != last; ++it) {
      const double gap = double(it->p[c]) - qc;
      if (best.beyond(gap * gap)) {
        if (gap > 0) break;
        continue;
      }
      best.add(column_distance2(q, it->p), &*it);
    }
    return;
  }
  const auto mid = std::partition_point(first, last, [&](const Entry& e) { return e.p[c] < qc; });
  for (auto it = mid; it != last; ++it) {
    const double gap = double(it->p[c]) - qc;
    if (best.beyond(gap * gap)) break;
    best.add(column_distance2(q, it->p), &*it);
  }
  for (auto it = mid; it != first;) {
    --it;
    const double gap = qc - double(it->p[c]);
    if (best.beyond(gap * gap)) break;
    best.add(column_distance2(q, it->p), &*it);
  }
}

// The columns at ring `ring` around the query's (ca, cb) (ring 0: its own), those that may hold
// a nearer point than best's worst. `ua`, `ub`: the query's position in column widths.
void PointColumns::search_ring(const Point3f& q, double ua, double ub, long ring,
                               Best& best) const {
  const long ca = static_cast<long>(std::floor(ua)), cb = static_cast<long>(std::floor(ub));
  for (long ia = std::max(0L, ca - ring); ia <= std::min(ga_ - 1, ca + ring); ++ia) {
    const bool side = ia == ca - ring || ia == ca + ring;
    const long step = side ? 1 : 2 * ring;  // inside the square: its two ends only
    const double ga = gap_to(ua, ia);
    for (long ib = cb - ring; ib <= cb + ring; ib += step) {
      if (ib < 0 || ib >= gb_) continue;
      const double gb = gap_to(ub, ib);
      if (best.beyond((ga * ga + gb * gb) * h_ * h_)) continue;
      scan_column(q, static_cast<std::size_t>(ia * gb_ + ib), best);
    }
    if (ring == 0) break;
  }
}

bool PointColumns::knn(const Point3f& q, std::size_t k, std::uint32_t* indices, double* distances2,
                       double* next) const {
  if (entries_.size() <= k) return false;
  const double ua = cell(q[axis_[0]], 0), ub = cell(q[axis_[1]], 1);
  if (!(std::fabs(ua) < kFar && std::fabs(ub) < kFar)) return false;
  Best best;
  best.capacity = k + 1;
  for (long ring = 0; ring <= kMaxRings; ++ring) {
    search_ring(q, ua, ub, ring, best);
    // Every column not searched yet is at least `reach` column widths away.
    const double fa = ua - std::floor(ua), fb = ub - std::floor(ub);
    const double reach = std::min({ring + 1 - fa, ring + fa, ring + 1 - fb, ring + fb}) - kSlack;
    if (!best.beyond(reach * reach * h_ * h_)) continue;
    if (!settled_by_distance(q, best, k)) return false;
    for (std::size_t j = 0; j < k; ++j) {
      indices[j] = best.e[j]->index;
      distances2[j] = best.d[j];
    }
    if (next != nullptr) *next = best.d[k];
    return true;
  }
  return false;
}

PsnrSearch::PsnrSearch(const std::vector<Point3f>& points, const std::vector<Point3f>* queries,
                       double tie_threshold)
    : points_(points) {
  if (queries == nullptr || queries->empty() || points.size() < 3) return;
  grid_ = std::make_unique<PointColumns>(points);
  const std::size_t samples = std::min(kSampleQueries, queries->size());
  const std::size_t step = queries->size() / samples;
  std::size_t to_tree = 0;
  for (std::size_t s = 0; s < samples; ++s) {
    std::uint32_t idx[kSampleRun];
    double d2[kSampleRun];
    const Point3f& q = (*queries)[s * step];
    double next = 0;
    if (!grid_->knn(q, 1, idx, d2, &next)) {
      ++to_tree;
    } else if (!(next - d2[0] >= tie_threshold) && !grid_->knn(q, kSampleRun, idx, d2)) {
      ++to_tree;
    }
  }
  if (static_cast<double>(to_tree) > kMaxTreeShare * static_cast<double>(samples)) {
    grid_.reset();
  }
}

PsnrSearch::~PsnrSearch() = default;

std::size_t PsnrSearch::knn(const Point3f& query, std::size_t k, std::uint32_t* indices,
                            double* distances2) const {
  if (grid_ && grid_->knn(query, k, indices, distances2)) return k;
  return tree().knn(query, k, indices, distances2);
}

const MpegTree& PsnrSearch::tree() const {
  std::call_once(tree_once_, [this] { tree_ = std::make_unique<MpegTree>(points_); });
  return *tree_;
}

}  // namespace qm3d::pointcloud::detail
