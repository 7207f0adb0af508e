// qm3d's keypoint rule for GraphSIM / MS-GraphSIM when no keypoint file is given
// (graphsim_engine.h choose_keypoints). The authors draw keypoints at random, unseeded, weighted by
// a local variation score (Chen et al., "Fast resampling of three-dimensional point clouds via
// graphs", IEEE TSP 2017, as their keypoint script computes it), so published numbers used
// keypoints nobody can draw again. qm3d computes the same score in float64 and draws with its own
// seeded generator:
// 1. The rows are ordered by (z, x, y), ties by file order (the authors' sortrows [3 1 2]).
// 2. K = min(50, N). Each row's K nearest rows (itself at distance 0 included), ascending, ties to
//    the lower row of that order; the first entry is dropped, the other K - 1 are its neighbours.
// 3. r = the largest K-th nearest distance over the rows round(linspace(1, N, 100)).
// 4. A filter: row i's new position is sum_j w_j z_j over its neighbours, w_j proportional to
//    exp(-(d_j / (r / 2))^2) and summing to 1 (the row keeps its position when the raw weights sum
//    to 1e-6 or less). z^(o) = the filter applied o times; the score is |z - z^(4)|^2.
// 5. `count` draws with replacement, u from std::mt19937_64(seed) as (u64 >> 11) * 2^-53, each the
//    row i with e_i <= u < e_(i+1), e = [0, cumsum(score) / sum(score)] (last edge 1); uniform when
//    every score is 0. The rows are returned in file order numbering, in drawing order.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "graphsim_engine.h"

namespace qm3d::pointcloud::detail {
namespace {

constexpr std::size_t kVariationNeighbours = 50;  // K of the authors' computeVariation
constexpr int kRadiusSamples = 100;               // rows of round(linspace(1, N, 100))
constexpr int kFilterOrder = 4;                   // the score column used (filter length 4)
constexpr double kMinWeightSum = 1e-6;            // below: the row keeps its position

int thread_count(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

/// The search radius (squared) over the previous query's K-th distance: neighbouring queries (in
/// (z, x, y) order) have similar spacing.
constexpr double kRadiusMargin = 1.5;

/// The k nearest rows (tree input indices) of a query, ascending, ties to the lower index, by
/// radius searches: a search of squared radius R finds every point with d^2 < R; once it holds
/// k points, every point tied with the k-th is among them (its d^2 < R too), so the result does
/// not depend on R, only the work does. R follows the previous query's K-th distance; a search
/// that holds fewer than K points falls back to a k-NN search for the K-th distance.
class NearestRows {
 public:
  NearestRows(const KdTree& tree, const std::vector<Vec3>& points, std::size_t k)
      : tree_(tree), points_(points), k_(k) {}

  const std::vector<std::uint32_t>& of(std::size_t query) {
    const Vec3& q = points_[query];
    if (radius2_ > 0) tree_.radius_search(q, radius2_ * kRadiusMargin, found_);
    if (!(radius2_ > 0) || found_.size() < k_) {
      // No radius known, or too small: the k-th distance, and every point within it.
      tree_.knn_search(q, k_, found_);
      tree_.radius_search(q, std::nextafter(found_.back().distance2, HUGE_VAL), found_);
    }
    std::nth_element(
        found_.begin(), found_.begin() + static_cast<long>(k_ - 1), found_.end(),
        [](const Neighbour& a, const Neighbour& b) { return a.distance2 < b.distance2; });
    const double kth = found_[k_ - 1].distance2;
    all_.clear();
    for (const Neighbour& n : found_) {
      if (n.distance2 <= kth) all_.emplace_back(n.distance2, tree_.input_index()[n.index]);
    }
    std::sort(all_.begin(), all_.end());
    rows_.resize(k_);
    for (std::size_t j = 0; j < k_; ++j) rows_[j] = all_[j].second;
    radius2_ = kth;
    return rows_;
  }

 private:
  const KdTree& tree_;
  const std::vector<Vec3>& points_;
  std::size_t k_;
  double radius2_ = 0;
  std::vector<Neighbour> found_;
  std::vector<std::pair<double, std::uint32_t>> all_;
  std::vector<std::uint32_t> rows_;
};

/// The rows in (z, x, y) order, ties by file order: sorted position -> file row.
std::vector<std::size_t> zxy_order(const std::vector<Vec3>& positions) {
  std::vector<std::size_t> order(positions.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const Vec3 &p = positions[a], &q = positions[b];
    if (p[2] != q[2]) return p[2] < q[2];
    if (p[0] != q[0]) return p[0] < q[0];
    return p[1] < q[1];
  });
  return order;
}

/// The variation score of each row of `z` (already in (z, x, y) order).
std::vector<double> variation_scores(const std::vector<Vec3>& z, int threads) {
  const std::size_t n = z.size();
  const std::size_t k = std::min(kVariationNeighbours, n);
  const KdTree tree(z, threads);
  std::vector<std::uint32_t> neighbours(n * k);
  const long count = static_cast<long>(n);
#pragma omp parallel num_threads(thread_count(threads))
  {
    NearestRows nearest(tree, z, k);
#pragma omp for schedule(dynamic, 256)
    for (long i = 0; i < count; ++i) {
      const auto& rows = nearest.of(static_cast<std::size_t>(i));
      std::copy(rows.begin(), rows.end(), neighbours.begin() + i * static_cast<long>(k));
    }
  }
  double r = 0;
  for (int s = 0; s < kRadiusSamples; ++s) {
    const auto j = static_cast<std::size_t>(
        std::lround(1.0 + s * (static_cast<double>(n - 1) / (kRadiusSamples - 1))) - 1);
    r = std::max(r, std::sqrt(squared_distance(z[j], z[neighbours[j * k + k - 1]])));
  }
  std::vector<Vec3> current = z, next(n);
  for (int o = 0; o < kFilterOrder; ++o) {
#pragma omp parallel for num_threads(thread_count(threads)) schedule(static)
    for (long i = 0; i < count; ++i) {
      const std::size_t row = static_cast<std::size_t>(i);
      std::vector<double> w(k);
      double sum = 0, last_d2 = -1, last_w = 0;
      for (std::size_t j = 1; j < k; ++j) {
        // Neighbours come by distance: equal distances (shells of a voxel grid) share a weight.
        const double d2 = squared_distance(z[row], z[neighbours[row * k + j]]);
        if (d2 != last_d2) {
          const double t = std::sqrt(d2) / (r * 0.5);
          last_w = std::exp(-(t * t));
          last_d2 = d2;
        }
        w[j] = last_w;
        sum += w[j];
      }
      if (!(sum > kMinWeightSum)) {
        next[row] = current[row];
        continue;
      }
      Vec3 p{0, 0, 0};
      for (std::size_t j = 1; j < k; ++j) {
        const Vec3& q = current[neighbours[row * k + j]];
        for (int a = 0; a < 3; ++a) p[a] += (w[j] / sum) * q[a];
      }
      next[row] = p;
    }
    std::swap(current, next);
  }
  std::vector<double> score(n);
  for (std::size_t i = 0; i < n; ++i) score[i] = squared_distance(z[i], current[i]);
  return score;
}

}  // namespace

std::vector<std::size_t> choose_keypoints(const std::vector<Vec3>& positions, std::size_t count,
                                          std::uint64_t seed, int threads) {
  const std::vector<std::size_t> order = zxy_order(positions);
  std::vector<Vec3> z(positions.size());
  for (std::size_t i = 0; i < z.size(); ++i) z[i] = positions[order[i]];
  std::vector<double> score = variation_scores(z, threads);
  double total = 0;
  for (double s : score) total += s;
  if (!(total > 0) || !std::isfinite(total)) {
    std::fill(score.begin(), score.end(), 1.0);
    total = static_cast<double>(score.size());
  }
  std::vector<double> edges(score.size() + 1, 0.0);
  double running = 0;
  for (std::size_t i = 0; i < score.size(); ++i) {
    running += score[i];
    edges[i + 1] = running / total;
  }
  edges.back() = 1;
  std::mt19937_64 rng(seed);
  std::vector<std::size_t> out;
  out.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;
    const auto at = std::upper_bound(edges.begin(), edges.end(), u) - edges.begin() - 1;
    out.push_back(order[static_cast<std::size_t>(at)]);
  }
  return out;
}

}  // namespace qm3d::pointcloud::detail
