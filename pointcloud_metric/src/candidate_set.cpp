#include "candidate_set.h"

#include <algorithm>
#include <cstddef>
#include <limits>

#include "qm3d/common/cpu.h"

#if defined(__GNUC__) && defined(__x86_64__)
#define QM3D_CANDIDATES_AVX2 1
#include <immintrin.h>
#endif

namespace qm3d::pointcloud::detail {
namespace {

/// Candidates per vector step (AVX2: four doubles); the arrays are padded to a multiple of it.
constexpr std::size_t kLanes = 4;
/// knn() sorts lists up to this size whole (sort_by_distance's branch-free path for short lists
/// is faster than selecting the k + 1 first there); longer ones are selected first.
constexpr std::size_t kSortWhole = 32;

#if defined(QM3D_CANDIDATES_AVX2)
static_assert(sizeof(Neighbour) == 16 && offsetof(Neighbour, distance2) == 0 &&
                  offsetof(Neighbour, index) == 8,
              "the vector path stores Neighbour as {double, 64-bit index}");

/// For each 4-bit mask of selected lanes, the 32-bit lane permutation that moves the selected
/// 64-bit lanes to the front, in their order.
struct CompressTable {
  alignas(32) std::int32_t lanes[16][8];
};
constexpr CompressTable make_compress_table() {
  CompressTable t{};
  for (int mask = 0; mask < 16; ++mask) {
    int out = 0;
    for (int lane = 0; lane < 4; ++lane) {
      if (mask & (1 << lane)) {
        t.lanes[mask][2 * out] = 2 * lane;
        t.lanes[mask][2 * out + 1] = 2 * lane + 1;
        ++out;
      }
    }
    for (; out < 4; ++out) {  // unused lanes: anything
      t.lanes[mask][2 * out] = 0;
      t.lanes[mask][2 * out + 1] = 1;
    }
  }
  return t;
}
constexpr CompressTable kCompress = make_compress_table();

// distances() and select_scalar() four candidates at a time: the same squared distances
// ((dx dx + dy dy) + dz dz, each operation an IEEE vector operation that rounds as the scalar
// one; the avx2 target has no FMA to contract them into), the same comparison, the selected
// candidates packed to the front in order and stored as Neighbours. Reads the arrays up to `n`
// rounded up to a multiple of 4 (the padding), selects among the first `n` only (whatever the
// bound, +infinity included), writes up to that many entries of `out`; returns how many were
// selected.
template <bool kStrict>
__attribute__((target("avx2"))) std::size_t select_avx2(const Vec3& q, const double* x,
                                                        const double* y, const double* z,
                                                        const std::uint32_t* index, std::size_t n,
                                                        double bound2, Neighbour* out) {
  const __m256d qx = _mm256_set1_pd(q[0]);
  const __m256d qy = _mm256_set1_pd(q[1]);
  const __m256d qz = _mm256_set1_pd(q[2]);
  const __m256d bound = _mm256_set1_pd(bound2);
  std::size_t m = 0;
  for (std::size_t j = 0; j < n; j += kLanes) {
    const __m256d dx = _mm256_sub_pd(qx, _mm256_loadu_pd(x + j));
    const __m256d dy = _mm256_sub_pd(qy, _mm256_loadu_pd(y + j));
    const __m256d dz = _mm256_sub_pd(qz, _mm256_loadu_pd(z + j));
    const __m256d d2 = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)),
                                     _mm256_mul_pd(dz, dz));
    int mask = _mm256_movemask_pd(_mm256_cmp_pd(d2, bound, kStrict ? _CMP_LT_OQ : _CMP_LE_OQ));
    if (n - j < kLanes) mask &= (1 << (n - j)) - 1;  // the padding's lanes
    const __m256i perm = _mm256_load_si256(reinterpret_cast<const __m256i*>(kCompress.lanes[mask]));
    const __m256d d =
        _mm256_castsi256_pd(_mm256_permutevar8x32_epi32(_mm256_castpd_si256(d2), perm));
    const __m256d i = _mm256_castsi256_pd(_mm256_permutevar8x32_epi32(
        _mm256_cvtepu32_epi64(_mm_loadu_si128(reinterpret_cast<const __m128i*>(index + j))), perm));
    const __m256d lo = _mm256_unpacklo_pd(d, i);  // {d0, i0, d2, i2}
    const __m256d hi = _mm256_unpackhi_pd(d, i);  // {d1, i1, d3, i3}
    double* o = reinterpret_cast<double*>(out + m);
    _mm256_storeu_pd(o, _mm256_permute2f128_pd(lo, hi, 0x20));
    _mm256_storeu_pd(o + 4, _mm256_permute2f128_pd(lo, hi, 0x31));
    m += static_cast<std::size_t>(__builtin_popcount(static_cast<unsigned>(mask)));
  }
  return m;
}
#endif

}  // namespace

Box box_of(const std::vector<Vec3>& points, std::uint32_t first, std::uint32_t last) {
  Box b{points[first], points[first]};
  for (std::uint32_t i = first + 1; i < last; ++i) {
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = std::min(b.lo[a], points[i][a]);
      b.hi[a] = std::max(b.hi[a], points[i][a]);
    }
  }
  return b;
}

void CandidateSet::gather(const KdTree& tree, const Box& box, double radius2) {
  tree.box_search(box.lo, box.hi, radius2, index_);
  size_ = index_.size();
  const std::size_t padded = (size_ + kLanes - 1) / kLanes * kLanes;
  index_.resize(padded, 0);
  x_.resize(padded);
  y_.resize(padded);
  z_.resize(padded);
  d2_.resize(padded);
  for (std::size_t j = 0; j < size_; ++j) {
    const Vec3& p = tree.points()[index_[j]];
    x_[j] = p[0];
    y_[j] = p[1];
    z_[j] = p[2];
  }
  constexpr double kFar = std::numeric_limits<double>::infinity();  // squared distance +inf
  for (std::size_t j = size_; j < padded; ++j) x_[j] = y_[j] = z_[j] = kFar;
  if (selected_.size() < padded) selected_.resize(padded);
}

// d2 = dx*dx + dy*dy + dz*dz with d = q - p, the order of squared_distance (a plain loop the
// compiler vectorises; without FMA contraction every lane rounds as the scalar code does).
void CandidateSet::distances(const Vec3& q) {
  const std::size_t n = size_;
  const double* x = x_.data();
  const double* y = y_.data();
  const double* z = z_.data();
  double* d2 = d2_.data();
  for (std::size_t j = 0; j < n; ++j) {
    const double dx = q[0] - x[j];
    const double dy = q[1] - y[j];
    const double dz = q[2] - z[j];
    d2[j] = dx * dx + dy * dy + dz * dz;
  }
}

// Keeps the candidates with d2 < bound2 (strict) or d2 <= bound2, branch-free: every candidate
// is written and the output position advances only when it passes.
// Two passes: count (vectorised), then write; the output is sized once to count + 1 so that
// the branch-free writes never run past it.
template <bool kStrict>
std::size_t CandidateSet::select_scalar(double bound2, std::vector<Neighbour>& out) const {
  const std::size_t n = size_;
  const double* d2 = d2_.data();
  std::size_t count = 0;
  for (std::size_t j = 0; j < n; ++j) count += kStrict ? (d2[j] < bound2) : (d2[j] <= bound2);
  out.resize(count + 1);
  Neighbour* o = out.data();
  std::size_t m = 0;
  for (std::size_t j = 0; j < n && m < count; ++j) {
    o[m] = Neighbour{d2[j], index_[j]};
    m += kStrict ? (d2[j] < bound2) : (d2[j] <= bound2);
  }
  out.resize(count);
  return count;
}

// The candidates with d2 < bound2 (kStrict) or d2 <= bound2, in tree order, into selected_: by
// the vector path where the processor has AVX2 (the same list, bit for bit), else the scalar one.
template <bool kStrict>
CandidateSet::Selection CandidateSet::select(const Vec3& q, double bound2) {
#if defined(QM3D_CANDIDATES_AVX2)
  if (cpu_has_avx2()) {
    const std::size_t m = select_avx2<kStrict>(q, x_.data(), y_.data(), z_.data(), index_.data(),
                                               size_, bound2, selected_.data());
    return Selection{selected_.data(), m};
  }
#endif
  distances(q);
  const std::size_t m = select_scalar<kStrict>(bound2, selected_);
  return Selection{selected_.data(), m};
}

template <bool kStrict>
void CandidateSet::select(const Vec3& q, double bound2, std::vector<Neighbour>& out) {
  const Selection s = select<kStrict>(q, bound2);
  out.assign(s.data, s.data + s.count);
}

CandidateSet::Selection CandidateSet::radius(const Vec3& q, double radius2) {
  return select<true>(q, radius2);
}

void CandidateSet::radius(const Vec3& q, double radius2, std::vector<Neighbour>& out) {
  select<true>(q, radius2, out);
}

CandidateSet::Knn CandidateSet::knn(const Vec3& q, std::size_t k, double knn_bound2,
                                    std::vector<Neighbour>& nearest) {
  select<false>(q, knn_bound2, survivors_);  // d2 <= bound: no NaN distance survives
  k = std::min(k, survivors_.size());
  Knn out;
  nearest.clear();
  if (k == 0) return out;
  // The k + 1 first in (distance, index) order: the list, and whether the next one ties the k-th.
  // Selected in linear time, then sorted: the order is total (distinct indices, no NaN), so they
  // are the first k + 1 entries of the fully sorted list, in its order.
  const std::size_t keep = std::min(k + 1, survivors_.size());
  if (survivors_.size() <= kSortWhole) {
    sort_by_distance(survivors_);
    nearest.assign(survivors_.begin(), survivors_.begin() + std::ptrdiff_t(keep));
  } else {
    std::nth_element(survivors_.begin(), survivors_.begin() + std::ptrdiff_t(keep - 1),
                     survivors_.end(), NeighbourOrder{});
    nearest.assign(survivors_.begin(), survivors_.begin() + std::ptrdiff_t(keep));
    sort_by_distance(nearest);
  }
  out.kth_distance2 = nearest[k - 1].distance2;
  out.tie_at_kth = keep > k && nearest[k].distance2 == out.kth_distance2;
  nearest.resize(k);
  return out;
}

}  // namespace qm3d::pointcloud::detail
