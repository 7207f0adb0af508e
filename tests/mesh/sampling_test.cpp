#include "qm3d/mesh/sampling.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <string>

#include "qm3d/common/error.h"

namespace qm3d::mesh {
namespace {

// Three right triangles far apart along x, legs 1, 3 and 10: areas 0.5, 4.5 and 50.
constexpr double kLegs[] = {1, 3, 10};
constexpr double kOffsetX[] = {0, 10, 20};

ColoredMesh three_triangles(const Rgb& color) {
  ColoredMesh m;
  for (int t = 0; t < 3; ++t) {
    m.positions.push_back({kOffsetX[t], 0, 0});
    m.positions.push_back({kOffsetX[t] + kLegs[t], 0, 0});
    m.positions.push_back({kOffsetX[t], kLegs[t], 0});
    const auto base = static_cast<std::uint32_t>(3 * t);
    m.triangles.push_back({base, base + 1, base + 2});
  }
  m.colors.assign(m.positions.size(), color);
  return m;
}

int triangle_of(const Vec3& p) { return p[0] < 5 ? 0 : p[0] < 15 ? 1 : 2; }

TEST(Sampling, TrianglesAreChosenInProportionToTheirArea) {
  constexpr std::size_t kPoints = 200000;
  const ColoredCloud cloud = sample_surface(three_triangles({0, 0, 0}), {kPoints, 0, 7});
  ASSERT_EQ(cloud.size(), kPoints);
  double counts[3] = {0, 0, 0};
  for (const Vec3& p : cloud.positions) ++counts[triangle_of(p)];
  const double total_area = 0.5 + 4.5 + 50;
  double chi_square = 0;
  for (int t = 0; t < 3; ++t) {
    const double expected = kPoints * 0.5 * kLegs[t] * kLegs[t] / total_area;
    chi_square += (counts[t] - expected) * (counts[t] - expected) / expected;
  }
  // 2 degrees of freedom: P(chi2 > 13.82) = 0.001.
  EXPECT_LT(chi_square, 13.82) << counts[0] << " " << counts[1] << " " << counts[2];
}

TEST(Sampling, PointsAreUniformInsideATriangleAndOnIt) {
  const ColoredCloud cloud = sample_surface(three_triangles({0, 0, 0}), {100000, 0, 3});
  double in_big = 0, left_half = 0;
  for (const Vec3& p : cloud.positions) {
    const int t = triangle_of(p);
    const double x = p[0] - kOffsetX[t], y = p[1];
    ASSERT_EQ(p[2], 0.0);
    ASSERT_GE(x, -1e-12);
    ASSERT_GE(y, -1e-12);
    ASSERT_LE(x + y, kLegs[t] * (1 + 1e-12));
    if (t != 2) continue;
    ++in_big;
    left_half += x < 5 ? 1 : 0;
  }
  // The part of the big triangle with x < 5 has area 50 - 12.5 = 37.5, i.e. 3/4.
  EXPECT_NEAR(left_half / in_big, 0.75, 0.01);
}

TEST(Sampling, FlatColourIsReproducedExactly) {
  const Rgb c{0.2, 0.4, 0.6};
  const ColoredCloud cloud = sample_surface(three_triangles(c), {5000, 0, 1});
  for (const Rgb& s : cloud.colors) {
    ASSERT_EQ(s.r, c.r);
    ASSERT_EQ(s.g, c.g);
    ASSERT_EQ(s.b, c.b);
  }
}

TEST(Sampling, ColourIsLinearOnAGradient) {
  ColoredMesh m;
  m.positions = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}};
  m.colors = {{0, 0, 0.5}, {1, 0, 0.5}, {0, 1, 0.5}};  // r = x / 10, g = y / 10
  m.triangles = {{0, 1, 2}};
  const ColoredCloud cloud = sample_surface(m, {5000, 0, 9});
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    EXPECT_NEAR(cloud.colors[i].r, cloud.positions[i][0] / 10, 1e-12);
    EXPECT_NEAR(cloud.colors[i].g, cloud.positions[i][1] / 10, 1e-12);
    EXPECT_EQ(cloud.colors[i].b, 0.5);
  }
}

void expect_same(const ColoredCloud& a, const ColoredCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.positions[i], b.positions[i]) << i;
    ASSERT_EQ(a.colors[i].r, b.colors[i].r) << i;
  }
}

TEST(Sampling, SameSeedSameCloudOnAnyThreadCount) {
  const ColoredMesh m = three_triangles({0.1, 0.2, 0.3});
  omp_set_num_threads(1);
  const ColoredCloud one = sample_surface(m, {1000, 0, 42});
  omp_set_num_threads(2);
  const ColoredCloud two = sample_surface(m, {1000, 0, 42});
  expect_same(one, two);
  const ColoredCloud other = sample_surface(m, {1000, 0, 43});
  EXPECT_NE(one.positions, other.positions);
}

TEST(Sampling, DensityGivesPointsPerUnitArea) {
  const ColoredMesh m = three_triangles({0, 0, 0});
  EXPECT_EQ(sample_surface(m, {0, 2.0, 1}).size(), 110u);  // 2 * 55
  EXPECT_EQ(sample_count({0, 0.5, 1}, 55), 28u);           // round(27.5)
  EXPECT_EQ(sample_count({12, 0, 1}, 55), 12u);
}

TEST(Sampling, InvalidRequestsThrow) {
  ColoredMesh m = three_triangles({0, 0, 0});
  EXPECT_THROW(sample_surface(m, {10, 1.0, 1}), NumericError);  // both
  EXPECT_THROW(sample_surface(m, {0, 0, 1}), NumericError);     // neither
  EXPECT_THROW(sample_surface(m, {0, -1.0, 1}), NumericError);
  EXPECT_THROW(sample_surface(m, {0, 1e-9, 1}), NumericError);  // no point at all
  ColoredMesh flat = m;
  for (auto& p : flat.positions) p[1] = 0;  // every triangle degenerate
  EXPECT_THROW(sample_surface(flat, {10, 0, 1}), NumericError);
  m.colors.clear();
  EXPECT_THROW(sample_surface(m, {10, 0, 1}), NumericError);
}

// A density whose count does not fit (1e19 per unit area on 55: 5.5e20 points, past 2^64) or
// is past what one sampling draws is an error giving the count, never an empty cloud.
TEST(Sampling, AbsurdDensitiesAndCountsAreRefusedWithTheCountTheyWouldGive) {
  const ColoredMesh m = three_triangles({0, 0, 0});
  for (const double density : {1e19, 1e300, 1e9}) {
    try {
      sample_count({0, density, 1}, 55);
      ADD_FAILURE() << "no error for density " << density;
    } catch (const NumericError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("points on an area of 55, more than the 1000000000"), std::string::npos)
          << what;
    }
  }
  try {
    sample_surface(m, {0, 1e19, 1});
    ADD_FAILURE() << "no error";
  } catch (const NumericError& e) {
    EXPECT_NE(std::string(e.what()).find("gives 5.5e+20 points"), std::string::npos) << e.what();
  }
  EXPECT_THROW(sample_count({kMaxSamples + 1, 0, 1}, 55), NumericError);
  EXPECT_EQ(sample_count({kMaxSamples, 0, 1}, 55), kMaxSamples);
}

}  // namespace
}  // namespace qm3d::mesh
