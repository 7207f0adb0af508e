// psnr's column grid (src/psnr_search.h) against pc_error's tree (MpegTree): wherever the grid
// answers, its answer is the tree's (indices, distances, order); PsnrSearch as a whole gives the
// tree's answers for every query, with the grid or without.
#include "psnr_search.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <thread>

namespace qm3d::pointcloud::detail {
namespace {

std::vector<Point3f> sphere(std::size_t n, float radius, Point3f centre, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g;
  std::vector<Point3f> p(n);
  for (Point3f& v : p) {
    const float x = g(rng), y = g(rng), z = g(rng);
    const float r = std::sqrt(x * x + y * y + z * z);
    v = {centre[0] + radius * x / r, centre[1] + radius * y / r, centre[2] + radius * z / r};
  }
  return p;
}

std::vector<Point3f> jittered(const std::vector<Point3f>& p, float sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.0f, sigma);
  std::vector<Point3f> out = p;
  for (Point3f& v : out) {
    for (float& c : v) c += g(rng);
  }
  return out;
}

std::vector<Point3f> voxelised(const std::vector<Point3f>& p, float step) {
  std::vector<Point3f> out = p;
  for (Point3f& v : out) {
    for (float& c : v) c = std::round(c / step);
  }
  return out;
}

// Every query the grid answers for k neighbours: the tree's answer. `answered`: how many.
void check_grid_is_tree(const std::vector<Point3f>& points, const std::vector<Point3f>& queries,
                        std::size_t k, std::size_t& answered) {
  const PointColumns grid(points);
  const MpegTree tree(points);
  answered = 0;
  for (std::size_t q = 0; q < queries.size(); ++q) {
    std::uint32_t gi[kMaxNeighbours], ti[kMaxNeighbours];
    double gd[kMaxNeighbours], td[kMaxNeighbours];
    if (!grid.knn(queries[q], k, gi, gd)) continue;
    ++answered;
    ASSERT_EQ(tree.knn(queries[q], k, ti, td), k);
    for (std::size_t j = 0; j < k; ++j) {
      ASSERT_EQ(gi[j], ti[j]) << "query " << q << " neighbour " << j;
      ASSERT_EQ(gd[j], td[j]) << "query " << q << " neighbour " << j;
    }
  }
}

std::size_t expect_grid_is_tree(const std::vector<Point3f>& points,
                                const std::vector<Point3f>& queries, std::size_t k) {
  std::size_t answered = 0;
  check_grid_is_tree(points, queries, k, answered);
  return answered;
}

// PsnrSearch's answers (grid or tree) are the tree's, for the passes' queries.
void expect_search_is_tree(const std::vector<Point3f>& points, const std::vector<Point3f>& queries,
                           double threshold) {
  const PsnrSearch search(points, &queries, threshold);
  const MpegTree tree(points);
  // The passes' tie test, and the normals transfer's (exactly equal) when threshold is 0.
  const auto tied = [threshold](double x, double y) {
    return threshold > 0 ? std::fabs(y - x) < threshold : x == y;
  };
  for (std::size_t q = 0; q < queries.size(); ++q) {
    std::uint32_t si[kMaxNeighbours], ti[kMaxNeighbours];
    double sd[kMaxNeighbours], td[kMaxNeighbours];
    for (bool expand : {false, true}) {
      const std::size_t found = search.tie_run_knn(queries[q], 10, expand, tied, si, sd);
      ASSERT_EQ(found, tree.tie_run_knn(queries[q], 10, expand, tied, ti, td)) << "query " << q;
      for (std::size_t j = 0; j < found; ++j) {
        ASSERT_EQ(si[j], ti[j]) << "query " << q;
        ASSERT_EQ(sd[j], td[j]) << "query " << q;
      }
    }
    ASSERT_EQ(search.knn(queries[q], 1, si, sd), tree.knn(queries[q], 1, ti, td));
    ASSERT_EQ(si[0], ti[0]);
    ASSERT_EQ(sd[0], td[0]);
  }
}

TEST(PsnrSearch, GridAnswersAreTheTreesOnARandomCloud) {
  const std::vector<Point3f> b = sphere(20000, 1.0f, {0, 0, 0}, 1);
  const std::vector<Point3f> a = jittered(sphere(20000, 1.0f, {0, 0, 0}, 2), 0.002f, 3);
  for (std::size_t k : {1, 2, 3, 10}) {
    // The grid settles nearly every query of a cloud without ties (the test can fail).
    EXPECT_GT(expect_grid_is_tree(b, a, k), a.size() * 9 / 10) << "k " << k;
  }
  expect_search_is_tree(b, a, 1e-8);
  expect_search_is_tree(b, a, 1e-3);  // most first two tied: the run of ten from the grid
  expect_search_is_tree(b, a, 0);
}

TEST(PsnrSearch, GridAnswersAreTheTreesOnAVoxelisedCloudWithTies) {
  const std::vector<Point3f> b = voxelised(sphere(20000, 100.0f, {0, 0, 0}, 4), 1.0f);
  const std::vector<Point3f> a = voxelised(jittered(b, 0.7f, 5), 1.0f);
  for (std::size_t k : {1, 2, 10}) expect_grid_is_tree(b, a, k);
  const PsnrSearch search(b, &a, 1e-8);
  EXPECT_FALSE(search.uses_grid());  // ties nearly everywhere: the tree alone
  expect_search_is_tree(b, a, 1e-8);
}

TEST(PsnrSearch, GridAnswersAreTheTreesWithDuplicates) {
  std::vector<Point3f> b = sphere(5000, 1.0f, {0, 0, 0}, 6);
  for (std::size_t i = 0; i < 200; ++i) b.push_back(b[i * 7]);  // kept duplicates (dropdups 0)
  const std::vector<Point3f> a = jittered(b, 0.001f, 7);
  for (std::size_t k : {1, 2, 3}) expect_grid_is_tree(b, a, k);
  expect_search_is_tree(b, a, 1e-8);
  expect_search_is_tree(b, b, 1e-8);  // each point's own duplicate at distance 0
  expect_search_is_tree(b, b, 0);
}

TEST(PsnrSearch, GridAnswersAreTheTreesFarFromTheOrigin) {
  const std::vector<Point3f> b = sphere(20000, 10.0f, {1.0e5f, -3.0e5f, 2.0e5f}, 8);
  const std::vector<Point3f> a = jittered(b, 0.01f, 9);
  for (std::size_t k : {1, 2, 10}) {
    EXPECT_GT(expect_grid_is_tree(b, a, k), a.size() / 2) << "k " << k;
  }
  expect_search_is_tree(b, a, 1e-8);
}

TEST(PsnrSearch, TheTreeBuiltOnFirstUseFromTwoThreads) {
  std::vector<Point3f> b = sphere(20000, 1.0f, {0, 0, 0}, 11);
  for (std::size_t i = 0; i < 100; ++i) b.push_back(b[i * 97 + 5]);  // a few need the tree
  const std::vector<Point3f> a = jittered(b, 0.0001f, 12);
  const PsnrSearch search(b, &a, 1e-8);
  ASSERT_TRUE(search.uses_grid());
  const MpegTree tree(b);
  std::vector<std::uint32_t> found[2];
  const auto run = [&](int t) {
    for (std::size_t q = t; q < a.size(); q += 2) {
      std::uint32_t idx[kMaxNeighbours];
      double d2[kMaxNeighbours];
      search.knn(a[q], 1, idx, d2);
      found[t].push_back(idx[0]);
    }
  };
  std::thread other(run, 1);
  run(0);
  other.join();
  for (std::size_t q = 0; q < a.size(); ++q) {
    std::uint32_t idx[1];
    double d2[1];
    tree.knn(a[q], 1, idx, d2);
    ASSERT_EQ(found[q % 2][q / 2], idx[0]) << "query " << q;
  }
}

TEST(PsnrSearch, QueriesOutsideTheGridAndFlatClouds) {
  std::vector<Point3f> plane;  // a flat square (no extent in z), queried from off its box
  for (int i = 0; i < 100; ++i) {
    for (int j = 0; j < 100; ++j) plane.push_back({i * 0.013f + 0.001f * (j % 7), j * 0.011f, 0});
  }
  std::vector<Point3f> queries = jittered(plane, 0.05f, 10);
  for (Point3f& q : queries) q[2] += 0.3f;
  queries.push_back({-5, -5, -5});
  queries.push_back({50, 0, 0});
  for (std::size_t k : {1, 2, 10}) expect_grid_is_tree(plane, queries, k);
  expect_search_is_tree(plane, queries, 1e-8);
}

}  // namespace
}  // namespace qm3d::pointcloud::detail
