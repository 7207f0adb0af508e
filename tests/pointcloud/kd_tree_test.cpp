#include "kd_tree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

namespace qm3d::pointcloud::detail {
namespace {

std::vector<Vec3> random_points(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  std::vector<Vec3> p(n);
  for (Vec3& v : p) v = {g(rng), g(rng), g(rng) * 0.1};
  return p;
}

// Points on an integer grid (many exactly equal distances) plus duplicates.
std::vector<Vec3> grid_points() {
  std::vector<Vec3> p;
  for (int x = 0; x < 12; ++x)
    for (int y = 0; y < 12; ++y)
      for (int z = 0; z < 3; ++z) p.push_back({double(x), double(y), double(z)});
  p.push_back({3, 3, 1});
  p.push_back({3, 3, 1});
  return p;
}

std::vector<Neighbour> brute_radius(const KdTree& t, const Vec3& q, double r2) {
  std::vector<Neighbour> out;
  for (std::uint32_t i = 0; i < t.size(); ++i) {
    const double d2 = squared_distance(q, t.points()[i]);
    if (d2 < r2) out.push_back({d2, i});
  }
  sort_by_distance(out);
  return out;
}

void expect_same(const std::vector<Neighbour>& a, const std::vector<Neighbour>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].index, b[i].index) << i;
    EXPECT_EQ(a[i].distance2, b[i].distance2) << i;
  }
}

TEST(KdTree, KeepsEveryPointOnce) {
  const auto p = random_points(1000, 1);
  const KdTree t(p);
  ASSERT_EQ(t.size(), p.size());
  std::set<std::uint32_t> seen(t.input_index().begin(), t.input_index().end());
  EXPECT_EQ(seen.size(), p.size());
  for (std::size_t i = 0; i < t.size(); ++i) EXPECT_EQ(t.points()[i], p[t.input_index()[i]]);
}

TEST(KdTree, RadiusSearchEqualsBruteForce) {
  for (const auto& p : {random_points(3000, 2), grid_points()}) {
    const KdTree t(p);
    for (std::size_t q = 0; q < p.size(); q += 7) {
      for (double r2 : {0.0, 0.01, 0.25, 1.0, 2.0, 4.0}) {
        std::vector<Neighbour> got;
        t.radius_search(p[q], r2, got);
        sort_by_distance(got);
        expect_same(got, brute_radius(t, p[q], r2));
      }
    }
  }
}

TEST(KdTree, RadiusIsStrict) {
  const std::vector<Vec3> p{{0, 0, 0}, {1, 0, 0}, {0, 2, 0}};
  const KdTree t(p);
  std::vector<Neighbour> got;
  t.radius_search({0, 0, 0}, 1.0, got);
  EXPECT_EQ(got.size(), 1u);  // the point at distance exactly 1 is excluded
  t.radius_search({0, 0, 0}, std::nextafter(1.0, 2.0), got);
  EXPECT_EQ(got.size(), 2u);
}

TEST(KdTree, KnnEqualsBruteForceDistances) {
  for (const auto& p : {random_points(3000, 3), grid_points()}) {
    const KdTree t(p);
    for (std::size_t q = 0; q < p.size(); q += 5) {
      for (std::size_t k : {1, 5, 20}) {
        std::vector<Neighbour> got;
        t.knn_search(p[q], k, got);
        const auto all = brute_radius(t, p[q], 1e300);
        ASSERT_EQ(got.size(), k);
        for (std::size_t i = 0; i < k; ++i) EXPECT_EQ(got[i].distance2, all[i].distance2);
        EXPECT_EQ(got[0].distance2, 0.0);
      }
    }
  }
}

TEST(KdTree, KnnOnSmallCloudReturnsEveryPoint) {
  const auto p = random_points(7, 4);
  const KdTree t(p);
  std::vector<Neighbour> got;
  t.knn_search({0, 0, 0}, 20, got);
  EXPECT_EQ(got.size(), 7u);
  EXPECT_TRUE(std::is_sorted(got.begin(), got.end(),
                             [](auto& a, auto& b) { return a.distance2 < b.distance2; }));
}

TEST(KdTree, CombinedSearchEqualsSeparateSearches) {
  const auto p = random_points(5000, 5);
  const KdTree t(p);
  std::vector<Neighbour> knn, within, knn2, within2;
  for (std::size_t q = 0; q < p.size(); q += 11) {
    for (double r2 : {0.001, 0.05, 0.3}) {
      t.knn_radius_search(p[q], 20, r2, knn, within);
      t.knn_search(p[q], 20, knn2);
      t.radius_search(p[q], r2, within2);
      expect_same(knn, knn2);
      sort_by_distance(within);
      sort_by_distance(within2);
      expect_same(within, within2);
    }
  }
}

TEST(KdTree, DoesNotDependOnThreadCount) {
  const auto p = random_points(200000, 6);
  const KdTree one(p, 1);
  const KdTree two(p, 2);
  EXPECT_EQ(one.input_index(), two.input_index());
}

TEST(KdTree, EmptyTree) {
  const KdTree t(std::vector<Vec3>{});
  std::vector<Neighbour> got{{1, 1}};
  t.radius_search({0, 0, 0}, 1, got);
  EXPECT_TRUE(got.empty());
  t.knn_search({0, 0, 0}, 3, got);
  EXPECT_TRUE(got.empty());
}

}  // namespace
}  // namespace qm3d::pointcloud::detail
