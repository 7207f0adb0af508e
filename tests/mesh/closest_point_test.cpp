// FaceBoxTree and project_on_triangle (closest_point.h) against CGAL itself: the same projected
// point on every kind of triangle, and the same closest point and face as CGAL's AABB tree for
// every query and hint, bit for bit, on smooth, noisy and quantised meshes (where equidistant
// faces make the traversal order decide), whatever the thread count of the build.
#include "closest_point.h"

#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_tree/internal/AABB_search_tree.h>
#include <boost/iterator/counting_iterator.hpp>
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <numeric>
#include <random>

#include "../test_paths.h"
#include "cgal_mesh.h"
#include "qm3d/mesh/mesh_io.h"

namespace qm3d::mesh::detail {
namespace {

bool same_bits(const Vec3& a, const Vec3& b) { return std::memcmp(&a, &b, sizeof(Vec3)) == 0; }

Vec3 cgal_projection(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& q) {
  const Point r = Kernel().construct_projected_point_3_object()(
      Kernel::Triangle_3(to_point(a), to_point(b), to_point(c)), to_point(q));
  return {r.x(), r.y(), r.z()};
}

// Triangles of every kind CGAL's projection distinguishes: general, needle, collinear (its
// degenerate-plane branch, each edge the longest in turn), repeated and identical corners, on
// integer coordinates (quantised meshes) and random ones.
std::vector<std::array<Vec3, 3>> triangle_zoo(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  std::uniform_int_distribution<int> grid(-3, 3);
  const auto random_point = [&] { return Vec3{u(rng), u(rng), u(rng)}; };
  const auto grid_point = [&] { return Vec3{double(grid(rng)), double(grid(rng)), double(grid(rng))}; };
  std::vector<std::array<Vec3, 3>> out;
  for (int i = 0; i < 300; ++i) {
    const Vec3 a = random_point(), b = random_point(), c = random_point();
    const Vec3 ga = grid_point(), gb = grid_point(), gc = grid_point();
    const double t = u(rng);
    const Vec3 on_ab{a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])};
    const Vec3 beyond{2 * gb[0] - ga[0], 2 * gb[1] - ga[1], 2 * gb[2] - ga[2]};
    for (const std::array<Vec3, 3>& tri :
         {std::array<Vec3, 3>{a, b, c}, {ga, gb, gc}, {a, b, on_ab}, {on_ab, a, b}, {b, on_ab, a},
          {ga, gb, beyond}, {a, a, b}, {a, b, b}, {a, a, a}}) {
      out.push_back(tri);
    }
  }
  return out;
}

TEST(ClosestPoint, ProjectionOnATriangleIsCgalsBitForBit) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2, 2);
  std::uniform_int_distribution<int> grid(-4, 4);
  std::size_t checked = 0;
  for (const auto& t : triangle_zoo(rng)) {
    std::vector<Vec3> queries{t[0], t[1], t[2]};  // the corners: equal corner distances
    for (int k = 0; k < 12; ++k) {
      queries.push_back(k % 2 ? Vec3{u(rng), u(rng), u(rng)}
                              : Vec3{double(grid(rng)), double(grid(rng)), double(grid(rng))});
    }
    for (const Vec3& q : queries) {
      const Vec3 ours = project_on_triangle(t[0], t[1], t[2], q);
      const Vec3 cgal = cgal_projection(t[0], t[1], t[2], q);
      ASSERT_TRUE(same_bits(ours, cgal))
          << "query (" << q[0] << ", " << q[1] << ", " << q[2] << ") gives (" << ours[0] << ", "
          << ours[1] << ", " << ours[2] << "), CGAL (" << cgal[0] << ", " << cgal[1] << ", "
          << cgal[2] << ")";
      ++checked;
    }
  }
  EXPECT_GT(checked, 40000u);
}

// CGAL's tree over the faces as MEPP2 (and qm3d before FaceBoxTree) builds it.
using Tree = CGAL::AABB_tree<FaceTraits>;

// Every vertex of `queries` (and a jittered copy) on `target`, from two hints each: CGAL's own
// default (the nearest face's first corner) and a fixed far one; CGAL and FaceBoxTree (built
// with 1 and 2 threads) must agree on the point and the face.
void expect_cgals_answers(const ColoredMesh& target, const std::vector<Vec3>& queries) {
  HalfedgeMesh mesh;  // views of the target's arrays: all the maps read
  mesh.positions = {target.positions.data(), target.positions.size()};
  mesh.triangles = {target.triangles.data(), target.triangles.size()};
  Tree cgal(boost::counting_iterator<std::uint32_t>(0),
            boost::counting_iterator<std::uint32_t>(std::uint32_t(target.triangles.size())),
            FaceTriangleMap{&mesh}, FacePointMap{&mesh});
  cgal.accelerate_distance_queries();
  cgal.build();
  const ArrayView<Vec3>& positions = mesh.positions;
  const ArrayView<Triangle>& triangles = mesh.triangles;
  const Vec3 far_corner = target.positions[target.triangles.back()[2]];
  const Tree::Point_and_primitive_id far_hint(to_point(far_corner),
                                              std::uint32_t(target.triangles.size() - 1));
  for (int threads : {1, 2}) {
    const FaceBoxTree ours(positions, triangles, threads);
    std::size_t differing_faces = 0;
    for (const Vec3& q : queries) {
      for (const auto& hint : {cgal.best_hint(to_point(q)), far_hint}) {
        const auto expected = cgal.closest_point_and_primitive(to_point(q), hint);
        const ClosestPoint found = ours.closest(
            q, {{hint.first.x(), hint.first.y(), hint.first.z()}, hint.second});
        ASSERT_EQ(found.face, expected.second)
            << threads << " threads, query (" << q[0] << ", " << q[1] << ", " << q[2] << ")";
        ASSERT_TRUE(same_bits(found.point, {expected.first.x(), expected.first.y(),
                                            expected.first.z()}));
        differing_faces += expected.second != hint.second;
      }
    }
    EXPECT_GT(differing_faces, 0u);  // the traversal did replace hints
  }
}

std::vector<Vec3> with_jitter(const std::vector<Vec3>& points, double sigma, std::mt19937& rng) {
  std::normal_distribution<double> g(0, sigma);
  std::vector<Vec3> out = points;
  for (const Vec3& p : points) out.push_back({p[0] + g(rng), p[1] + g(rng), p[2] + g(rng)});
  return out;
}

TEST(ClosestPoint, FaceBoxTreeGivesCgalsPointAndFaceOnReferenceMeshes) {
  std::mt19937 rng(11);
  const auto dir = test::reference_dir();
  const std::pair<const char*, const char*> pairs[] = {
      {"cmdm/blob4_ref.off", "cmdm/blob4_bothnoise.off"},
      {"cmdm/monkey_simplified.obj", "cmdm/monkey2.obj"},
      // 6-bit quantisation: coincident vertices and zero-area faces, ties everywhere.
      {"quantised/blob5_pquant6.off", "cmdm/blob5_ref.off"},
      {"cmdm/blob5_ref.off", "quantised/blob5_pquant6.off"},
  };
  for (const auto& [target, query] : pairs) {
    SCOPED_TRACE(std::string(query) + " on " + target);
    const ColoredMesh t = read_mesh(dir / target).mesh;
    const ColoredMesh q = read_mesh(dir / query).mesh;
    expect_cgals_answers(t, with_jitter(q.positions, 1e-3, rng));
  }
}

// The nearest point by brute force, and whether another is exactly as near.
NearestPointIndex::Nearest brute_force_nearest(const std::vector<Vec3>& points,
                                               const std::vector<std::uint32_t>& ids,
                                               const Vec3& q) {
  NearestPointIndex::Nearest best;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double dx = q[0] - points[i][0], dy = q[1] - points[i][1], dz = q[2] - points[i][2];
    const double d2 = dx * dx + dy * dy + dz * dz;
    if (d2 < best_d2) {
      best_d2 = d2;
      best = {points[i], ids[i], false};
    } else if (d2 == best_d2) {
      best.tie = true;
    }
  }
  return best;
}

TEST(ClosestPoint, NearestPointIndexIsExactAndReportsTies) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1, 1);
  std::uniform_int_distribution<int> grid(-6, 6);
  for (const bool on_grid : {false, true}) {
    std::vector<Vec3> points;
    for (int i = 0; i < 3000; ++i) {
      points.push_back(on_grid ? Vec3{double(grid(rng)), double(grid(rng)), double(grid(rng))}
                               : Vec3{u(rng), u(rng), u(rng)});
    }
    for (int i = 0; i < 200; ++i) points.push_back(points[std::size_t(i) * 7]);  // duplicates
    // Every other point, each point with an id of its own.
    std::vector<std::uint32_t> which, ids(points.size()), chosen_ids;
    std::iota(ids.begin(), ids.end(), 1000u);
    std::vector<Vec3> chosen;
    for (std::uint32_t i = 0; i < points.size(); i += 2) {
      which.push_back(i);
      chosen.push_back(points[i]);
      chosen_ids.push_back(ids[i]);
    }
    std::size_t ties = 0;
    for (int threads : {1, 2}) {
      const NearestPointIndex index({points.data(), points.size()}, which, ids, threads);
      for (int k = 0; k < 2000; ++k) {
        const Vec3 q = k % 3 == 0 ? points[std::size_t(k)]
                                  : Vec3{grid(rng) / 2.0, grid(rng) / 2.0, u(rng) * 3};
        const auto expected = brute_force_nearest(chosen, chosen_ids, q);
        const auto found = index.nearest(q);
        ASSERT_EQ(found.tie, expected.tie) << k;
        if (!expected.tie) {
          ASSERT_EQ(found.id, expected.id);
          ASSERT_TRUE(same_bits(found.point, expected.point));
        } else {
          ++ties;
        }
      }
    }
    EXPECT_GT(ties, 50u);
  }
}

// Where the nearest vertex is unique, it is the hint CGAL's k-d tree (AABB_search_tree) gives.
TEST(ClosestPoint, UniqueNearestVertexIsCgalsHint) {
  using Traits = FaceTraits;
  for (const char* name : {"cmdm/blob4_bothnoise.off", "quantised/blob5_pquant6.off"}) {
    SCOPED_TRACE(name);
    const ColoredMesh mesh = read_mesh(test::reference_dir() / name).mesh;
    std::vector<std::uint32_t> ids(mesh.positions.size());
    std::iota(ids.begin(), ids.end(), 0u);
    std::vector<Traits::Point_and_primitive_id> hints;
    for (std::uint32_t v = 0; v < mesh.positions.size(); ++v) {
      hints.emplace_back(to_point(mesh.positions[v]), v);
    }
    const CGAL::AABB_search_tree<Traits> cgal(hints.begin(), hints.end());
    const NearestPointIndex index({mesh.positions.data(), mesh.positions.size()}, ids, ids, 2);
    const ColoredMesh other = read_mesh(test::reference_dir() / "cmdm/blob5_ref.off").mesh;
    std::size_t unique = 0;
    for (const Vec3& q : other.positions) {
      const auto found = index.nearest(q);
      if (found.tie) continue;
      const auto expected = cgal.closest_point(to_point(q));
      ASSERT_EQ(found.id, expected.second);
      ++unique;
    }
    EXPECT_GT(unique, other.positions.size() / 2);
  }
}

// An integer grid (heights 0 or 1) and queries on a half-integer lattice around it: distances tie
// between faces, between boxes and the current closest point, and between hints.
TEST(ClosestPoint, FaceBoxTreeGivesCgalsPointAndFaceOnAnIntegerGrid) {
  std::mt19937 rng(13);
  std::uniform_int_distribution<int> bump(0, 3);
  ColoredMesh grid;
  const int n = 24;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) grid.positions.push_back({double(i), double(j), bump(rng) == 0 ? 1.0 : 0.0});
  }
  const auto at = [n](int i, int j) { return static_cast<std::uint32_t>(i * n + j); };
  for (int i = 0; i + 1 < n; ++i) {
    for (int j = 0; j + 1 < n; ++j) {
      grid.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      grid.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  std::vector<Vec3> queries;
  for (int i = -2; i <= 2 * n + 2; ++i) {
    for (int j = -2; j <= 2 * n + 2; j += 3) {
      for (int k : {-2, 1, 3}) queries.push_back({i / 2.0, j / 2.0, k / 2.0});
    }
  }
  expect_cgals_answers(grid, queries);
}

}  // namespace
}  // namespace qm3d::mesh::detail
