#include "candidate_set.h"

#include <algorithm>

namespace qm3d::pointcloud::detail {

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
  const std::size_t n = index_.size();
  x_.resize(n);
  y_.resize(n);
  z_.resize(n);
  d2_.resize(n);
  for (std::size_t j = 0; j < n; ++j) {
    const Vec3& p = tree.points()[index_[j]];
    x_[j] = p[0];
    y_[j] = p[1];
    z_[j] = p[2];
  }
}

// d2 = dx*dx + dy*dy + dz*dz with d = q - p, the order of squared_distance (a plain loop the
// compiler vectorises; without FMA contraction every lane rounds as the scalar code does).
void CandidateSet::distances(const Vec3& q) {
  const std::size_t n = index_.size();
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
std::size_t CandidateSet::select(double bound2, std::vector<Neighbour>& out) const {
  const std::size_t n = index_.size();
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

void CandidateSet::radius(const Vec3& q, double radius2, std::vector<Neighbour>& out) {
  distances(q);
  select<true>(radius2, out);
}

CandidateSet::Knn CandidateSet::knn(const Vec3& q, std::size_t k, double knn_bound2,
                                    std::vector<Neighbour>& nearest) {
  distances(q);
  select<false>(knn_bound2, survivors_);
  sort_by_distance(survivors_);
  k = std::min(k, survivors_.size());
  nearest.assign(survivors_.begin(), survivors_.begin() + long(k));
  Knn out;
  if (k == 0) return out;
  out.kth_distance2 = nearest.back().distance2;
  out.tie_at_kth = survivors_.size() > k && survivors_[k].distance2 == out.kth_distance2;
  return out;
}

}  // namespace qm3d::pointcloud::detail
