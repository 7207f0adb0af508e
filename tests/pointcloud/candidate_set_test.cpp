#include "candidate_set.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace qm3d::pointcloud::detail {
namespace {

std::vector<Vec3> noisy_sphere(std::size_t n, unsigned seed, double noise) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  std::vector<Vec3> p(n);
  for (Vec3& v : p) {
    const double x = g(rng), y = g(rng), z = g(rng);
    const double s = 1 / std::sqrt(x * x + y * y + z * z);
    v = {x * s + noise * g(rng), y * s + noise * g(rng), z * s + noise * g(rng)};
  }
  return p;
}

void expect_same(std::vector<Neighbour> a, std::vector<Neighbour> b) {
  sort_by_distance(a);
  sort_by_distance(b);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].index, b[i].index);
    EXPECT_EQ(a[i].distance2, b[i].distance2);
  }
}

// Queries: the points of each leaf of `queries`; searched cloud: `data`.
TEST(CandidateSet, BatchedSearchesEqualTreeSearches) {
  const KdTree queries(noisy_sphere(4000, 1, 0.0));
  const KdTree data(noisy_sphere(6000, 2, 0.01));
  const double r2 = 0.05 * 0.05;
  CandidateSet near, reach;
  std::vector<Neighbour> got, nearest, tree_knn, tree_within;
  for (const auto& leaf : queries.leaves()) {
    const Box box = box_of(queries.points(), leaf[0], leaf[1]);
    near.gather(data, box, r2);
    reach.gather(data, box, 0.3 * 0.3);
    for (std::uint32_t i = leaf[0]; i < leaf[1]; ++i) {
      const Vec3& q = queries.points()[i];
      near.radius(q, r2, got);
      data.radius_search(q, r2, tree_within);
      expect_same(got, tree_within);

      data.knn_search(q, 20, tree_knn);
      const double bound2 = tree_knn.back().distance2 * 1.5;  // any bound >= the k-th distance
      ASSERT_LE(tree_knn.back().distance2, 0.3 * 0.3);
      const auto found = reach.knn(q, 20, bound2, nearest);
      EXPECT_EQ(found.kth_distance2, tree_knn.back().distance2);
      EXPECT_FALSE(found.tie_at_kth);
      ASSERT_EQ(nearest.size(), 20u);
      for (std::size_t k = 0; k < 20; ++k) {
        EXPECT_EQ(nearest[k].distance2, tree_knn[k].distance2);
        EXPECT_EQ(nearest[k].index, tree_knn[k].index);  // no ties on this cloud
      }
    }
  }
}

// radius() is the box's candidates filtered in tree order, with squared_distance's values, bit
// for bit (whichever path, vector or scalar, the processor takes); so is knn() before its sort.
TEST(CandidateSet, RadiusListsAreTheCandidatesInTreeOrder) {
  const KdTree tree(noisy_sphere(3000, 4, 0.01));
  const double r2 = 0.06 * 0.06;
  CandidateSet near;
  std::vector<std::uint32_t> candidates;
  std::vector<Neighbour> got, nearest;
  for (const auto& leaf : tree.leaves()) {
    const Box box = box_of(tree.points(), leaf[0], leaf[1]);
    near.gather(tree, box, r2);
    tree.box_search(box.lo, box.hi, r2, candidates);
    ASSERT_EQ(near.size(), candidates.size());
    for (std::uint32_t i = leaf[0]; i < leaf[1]; ++i) {
      const Vec3& q = tree.points()[i];
      std::vector<Neighbour> expected;
      for (std::uint32_t c : candidates) {
        const double d2 = squared_distance(q, tree.points()[c]);
        if (d2 < r2) expected.push_back(Neighbour{d2, c});
      }
      near.radius(q, r2, got);
      ASSERT_EQ(got.size(), expected.size());
      for (std::size_t k = 0; k < got.size(); ++k) {
        EXPECT_EQ(got[k].index, expected[k].index);
        EXPECT_EQ(got[k].distance2, expected[k].distance2);
      }
      // knn: every candidate within the bound (<=), sorted; here all of them.
      near.knn(q, candidates.size(), 1e300, nearest);
      ASSERT_EQ(nearest.size(), candidates.size());
    }
  }
}

TEST(CandidateSet, BoxSearchIsASupersetOfEveryQuerysBall) {
  const KdTree tree(noisy_sphere(5000, 3, 0.02));
  std::vector<std::uint32_t> box_points;
  std::vector<Neighbour> ball;
  for (std::size_t l = 0; l < tree.leaves().size(); l += 3) {
    const auto leaf = tree.leaves()[l];
    const Box box = box_of(tree.points(), leaf[0], leaf[1]);
    tree.box_search(box.lo, box.hi, 0.01, box_points);
    for (std::uint32_t i = leaf[0]; i < leaf[1]; ++i) {
      tree.radius_search(tree.points()[i], 0.01, ball);
      for (const Neighbour& n : ball) {
        EXPECT_TRUE(std::binary_search(box_points.begin(), box_points.end(), n.index));
      }
    }
  }
}

TEST(CandidateSet, TiesAreBrokenByIndexAndReportedAtTheKth) {
  // Eight points at the same distance from the origin query: the kNN keeps the lowest indices
  // and reports that the last place was a tie (the reference's choice is the tree's to make).
  std::vector<Vec3> p;
  for (int s = 0; s < 8; ++s)
    p.push_back({s & 1 ? 1.0 : -1.0, s & 2 ? 1.0 : -1.0, s & 4 ? 1.0 : -1.0});
  p.push_back({0, 0, 0});
  const KdTree tree(p);
  CandidateSet c;
  c.gather(tree, Box{{0, 0, 0}, {0, 0, 0}}, 10.0);
  std::vector<Neighbour> nearest;
  const auto found = c.knn({0, 0, 0}, 4, 10.0, nearest);
  EXPECT_TRUE(found.tie_at_kth);
  EXPECT_EQ(found.kth_distance2, 3.0);
  ASSERT_EQ(nearest.size(), 4u);
  EXPECT_EQ(nearest[0].distance2, 0.0);
  std::vector<std::uint32_t> corners;  // tree indices of the eight tied points
  for (std::uint32_t i = 0; i < tree.size(); ++i) {
    if (tree.input_index()[i] != 8) corners.push_back(i);
  }
  for (std::size_t k = 1; k < 4; ++k) {
    EXPECT_EQ(nearest[k].distance2, 3.0);
    EXPECT_EQ(nearest[k].index, corners[k - 1]);
  }
  EXPECT_FALSE(c.knn({0, 0, 0}, 9, 10.0, nearest).tie_at_kth);
}

}  // namespace
}  // namespace qm3d::pointcloud::detail
