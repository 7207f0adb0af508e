#include "kd_tree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
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

// NANOFLANN-1.1.7.md §5's worked example: the 1 x 4 x 4 grid p_i = (0, i / 4, i % 4). The root
// box spans y and z equally; 1.1.7's middleSplit_ compares the spread along the dim chosen so far
// (x: 0) and takes z, cuts at 1.5, and two Hoare passes leave the order below. From (0, 0, 1.5),
// p1 and p2 tie; the midpoint goes to the second child first, so p2 wins. (nanoflann >= 1.2.3
// splits on y and returns p1.)
TEST(KdTree, ReproducesNanoflann117OnTheSpecsGrid) {
  std::vector<Vec3> p;
  for (int i = 0; i < 16; ++i) p.push_back({0.0, double(i / 4), double(i % 4)});
  const KdTree t(p);
  const std::vector<std::uint32_t> order{0, 1, 13, 12, 4, 5, 9, 8, 7, 6, 10, 11, 3, 2, 14, 15};
  EXPECT_EQ(t.input_index(), order);
  ASSERT_EQ(t.leaves().size(), 2u);
  EXPECT_EQ(t.leaves()[0][1], 8u);

  const auto inputs = [&t](const std::vector<Neighbour>& r) {
    std::vector<std::uint32_t> out;
    for (const Neighbour& n : r) out.push_back(t.input_index()[n.index]);
    return out;
  };
  std::vector<Neighbour> got;
  t.knn_search({0, 0, 1.5}, 1, got);
  EXPECT_EQ(inputs(got), (std::vector<std::uint32_t>{2}));
  t.knn_search({0, 0, 1.5}, 2, got);
  EXPECT_EQ(inputs(got), (std::vector<std::uint32_t>{2, 1}));
  t.radius_search({0, 0, 1.5}, 0.3, got);
  EXPECT_EQ(inputs(got), (std::vector<std::uint32_t>{2, 1}));
}

// The rule of NANOFLANN-1.1.7.md §5: list every point in unpruned depth-first order, stable-sort
// by distance; the first k are the kNN. A radius search with an infinite radius prunes nothing,
// so it lists every point in that order; the kNN search, which prunes with its shrinking worst
// distance, must agree with it.
std::vector<std::uint32_t> dfs_rule(const KdTree& t, const Vec3& q) {
  std::vector<std::uint32_t> all(t.size());
  for (std::uint32_t i = 0; i < t.size(); ++i) all[i] = i;
  std::vector<Neighbour> traversal;
  t.radius_search(q, std::numeric_limits<double>::infinity(), traversal);
  std::vector<std::uint32_t> rank(t.size());
  for (std::size_t r = 0; r < traversal.size(); ++r) rank[traversal[r].index] = std::uint32_t(r);
  std::stable_sort(all.begin(), all.end(), [&](std::uint32_t a, std::uint32_t b) {
    const double da = squared_distance(q, t.points()[a]);
    const double db = squared_distance(q, t.points()[b]);
    return da < db || (da == db && rank[a] < rank[b]);
  });
  return all;
}

TEST(KdTree, KnnIsTheFirstKOfTheTraversalByDistance) {
  // Every query on a grid with duplicates meets ties; queries at cell midpoints tie on the
  // split planes themselves.
  const auto p = grid_points();
  const KdTree t(p);
  std::vector<Neighbour> got;
  for (std::size_t q = 0; q < p.size(); q += 3) {
    for (const Vec3& query : {p[q], Vec3{p[q][0] + 0.5, p[q][1], p[q][2] + 0.5}}) {
      const auto expected = dfs_rule(t, query);
      for (std::size_t k : {1, 4, 20}) {
        t.knn_search(query, k, got);
        ASSERT_EQ(got.size(), k);
        for (std::size_t i = 0; i < k; ++i) EXPECT_EQ(got[i].index, expected[i]) << q << " " << k;
      }
    }
  }
}

TEST(KdTree, RadiusOrderIsTheTraversalOrder) {
  const auto p = grid_points();
  const KdTree t(p);
  std::vector<Neighbour> all, within;
  for (std::size_t q = 0; q < p.size(); q += 5) {
    t.radius_search(p[q], std::numeric_limits<double>::infinity(), all);
    t.radius_search(p[q], 2.5, within);
    std::size_t next = 0;  // `within` must be `all` filtered by d2 < 2.5, in order
    for (const Neighbour& n : all) {
      if (n.distance2 < 2.5) {
        ASSERT_LT(next, within.size());
        EXPECT_EQ(within[next++].index, n.index);
      }
    }
    EXPECT_EQ(next, within.size());
  }
}

TEST(KdTree, SortedRadiusIsStdSortOfTheTraversal) {
  const auto p = grid_points();
  const KdTree t(p);
  std::vector<Neighbour> got, expected;
  for (std::size_t q = 0; q < p.size(); q += 5) {
    t.sorted_radius_search(p[q], 5.0, got);  // about 30 points, many tied: introsort's order
    t.radius_search(p[q], 5.0, expected);
    std::sort(expected.begin(), expected.end(),
              [](const Neighbour& a, const Neighbour& b) { return a.distance2 < b.distance2; });
    ASSERT_EQ(got.size(), expected.size());
    for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i].index, expected[i].index);
  }
}

// sort_by_distance orders by (distance, index) whatever the list's length and order (short lists
// take a rank-counting path on AVX2 machines, longer ones insertion sort or std::sort), ties,
// zeros of both signs and infinities included.
TEST(KdTree, SortByDistanceOrdersByDistanceThenIndex) {
  std::mt19937 rng(11);
  const double values[] = {0.0, -0.0, 1.0, 2.0, 2.5, std::numeric_limits<double>::infinity()};
  for (std::size_t n = 0; n <= 80; ++n) {
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<Neighbour> list(n);
      std::vector<std::uint32_t> indices(200);
      for (std::uint32_t k = 0; k < indices.size(); ++k) indices[k] = k * 7919u;
      std::shuffle(indices.begin(), indices.end(), rng);
      for (std::size_t k = 0; k < n; ++k) {
        const double d =
            trial % 2 ? values[rng() % 6] : std::uniform_real_distribution<>(0, 1)(rng);
        list[k] = Neighbour{d, indices[k]};
      }
      std::vector<Neighbour> expected = list;
      std::sort(expected.begin(), expected.end(), [](const Neighbour& a, const Neighbour& b) {
        return a.distance2 < b.distance2 || (a.distance2 == b.distance2 && a.index < b.index);
      });
      sort_by_distance(list);
      for (std::size_t k = 0; k < n; ++k) {
        EXPECT_EQ(list[k].index, expected[k].index);
        EXPECT_EQ(list[k].distance2, expected[k].distance2);
      }
    }
  }
}

TEST(KdTree, HasTies) {
  EXPECT_FALSE(has_ties({}));
  EXPECT_FALSE(has_ties({{1, 0}, {2, 1}}));
  EXPECT_TRUE(has_ties({{1, 0}, {2, 1}, {2, 2}}));
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
