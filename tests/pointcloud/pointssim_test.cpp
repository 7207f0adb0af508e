// PointSSIM (qm3d/pointcloud/pointssim.h; issue 41): every value of the reference table from the
// library, a cloud against itself, the same bits on 1 and 2 threads, bad input refused with one
// line naming the file, and the rules the reference's numbers depend on (the tie order of the
// neighbour search, the fused colours, the estimators on hand-made values).
#include "qm3d/pointcloud/pointssim.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "pointcloud/pointssim_reference.h"
#include "pointssim_internal.h"
#include "qm3d/common/error.h"
#include "qm3d/common/reading.h"
#include "qm3d/pointcloud/cloud_io.h"

namespace qm3d::pointcloud {
namespace {

using test::pointssim_dir;

ColoredCloud read(const std::string& name) {
  return read_cloud_data(pointssim_dir() / name, CloudFormat::kPly).cloud;
}

PointssimOptions all_values(int k) {
  PointssimOptions o;
  o.neighbours = k;
  o.attributes = parse_pointssim_attributes("all", "attributes");
  o.estimators = parse_pointssim_estimators("all", "estimators");
  o.poolings = parse_pointssim_poolings("all", "poolings");
  return o;
}

const NamedValues& values_of(const MetricResult& r, const std::string& direction) {
  if (direction == "BA") return r.dist_to_ref->values;
  if (direction == "AB") return r.ref_to_dist->values;
  return r.values;
}

TEST(Pointssim, EveryReferenceValueWithinTolerance) {
  const auto rows = test::pointssim_rows();
  ASSERT_EQ(rows.size(), 20u);
  std::size_t checked = 0;
  double worst = 0;
  std::string worst_column;
  for (const test::PointssimRow& row : rows) {
    SCOPED_TRACE(row.field("case") + " K " + row.field("K"));
    PointssimOptions o = all_values(std::stoi(row.field("K")));
    o.fit = row.field("fit_method") == "knn" ? PointssimFit::kKnn : PointssimFit::kRadius;
    o.fit_size = std::stod(row.field("fit_size"));
    const MetricResult r = compute_pointssim(read(row.field("fileA")), read(row.field("fileB")), o);
    EXPECT_EQ(r.ref_to_dist->per_element.size(), std::stoul(row.field("nA_in")));
    EXPECT_EQ(std::stoul(r.details.at("points").at("reference").dump()),
              std::stoul(row.field("nA")));
    EXPECT_EQ(std::stoul(r.details.at("points").at("distorted").dump()),
              std::stoul(row.field("nB")));
    for (const test::PointssimColumn& c : test::pointssim_columns(row)) {
      if (!test::pointssim_checked(row, c)) continue;
      const double expected = std::stod(row.field(c.column));
      const auto got = find_value(values_of(r, c.direction), c.name);
      ASSERT_TRUE(got.has_value()) << c.column;
      EXPECT_TRUE(test::pointssim_agrees(*got, expected))
          << c.column << ": " << *got << " vs " << expected;
      const double rel = std::abs(*got - expected) / std::abs(expected);
      if (rel > worst) {
        worst = rel;
        worst_column = row.field("case") + " K" + row.field("K") + " " + c.column;
      }
      ++checked;
    }
  }
  // 12 float-cloud rows x 252 + 8 voxel rows x 126 (geometry and colour).
  EXPECT_EQ(checked, 16u * 252 + 4u * 126);
  std::printf("worst relative difference %.3g (%s)\n", worst, worst_column.c_str());
}

TEST(Pointssim, ACloudAgainstItselfIsExactlyOne) {
  for (const char* name : {"sphere_2k_ref.ply", "vox1crop_ref.ply"}) {
    SCOPED_TRACE(name);
    PointssimOptions o = all_values(12);
    o.fit = PointssimFit::kKnn;
    o.fit_size = 12;
    const ColoredCloud c = read(name);
    const MetricResult r = compute_pointssim(c, c, o);
    EXPECT_EQ(r.score, 1.0);
    ASSERT_EQ(r.values.size(), 84u);
    for (const auto& [n, v] : r.values) EXPECT_EQ(v, 1.0) << n;
    for (double v : r.dist_to_ref->per_element) ASSERT_EQ(v, 1.0);
  }
}

TEST(Pointssim, OneAndTwoThreadsGiveTheSameBits) {
  const ColoredCloud a = read("vox1crop_ref.ply"), b = read("vox1crop_requant8.ply");
  PointssimOptions o = all_values(12);
  o.fit = PointssimFit::kRadius;
  o.fit_size = 3;
  o.threads = 1;
  const MetricResult one = compute_pointssim(a, b, o);
  o.threads = 2;
  const MetricResult two = compute_pointssim(a, b, o);
  ASSERT_EQ(one.values.size(), two.values.size());
  for (std::size_t k = 0; k < one.values.size(); ++k) {
    EXPECT_EQ(std::memcmp(&one.values[k].second, &two.values[k].second, sizeof(double)), 0)
        << one.values[k].first;
  }
  EXPECT_EQ(one.ref_to_dist->per_element, two.ref_to_dist->per_element);
  EXPECT_EQ(one.dist_to_ref->per_element, two.dist_to_ref->per_element);
}

TEST(Pointssim, DefaultsScoreColourVarianceMeanAndItsDirections) {
  PointssimOptions o;
  o.fit = PointssimFit::kKnn;
  o.fit_size = 12;
  const ColoredCloud a = read("sphere_2k_ref.ply"), b = read("sphere_2k_cnoise30.ply");
  const MetricResult r = compute_pointssim(a, b, o);
  EXPECT_EQ(r.values.size(), 4u);  // geom, norm, curv, color x var x mean
  EXPECT_EQ(r.score, *find_value(r.values, "color_var_mean"));
  EXPECT_EQ(r.ref_to_dist->score, *find_value(r.ref_to_dist->values, "color_var_mean"));
  EXPECT_EQ(r.score, std::min(r.ref_to_dist->score, r.dist_to_ref->score));
  EXPECT_LT(r.score, 1.0);
  // Without colours: geom_var_mean.
  ColoredCloud plain_a = a, plain_b = b;
  plain_a.colors.clear();
  plain_b.colors.clear();
  const MetricResult g = compute_pointssim(plain_a, plain_b, o);
  EXPECT_EQ(g.values.size(), 3u);
  EXPECT_EQ(g.score, *find_value(g.values, "geom_var_mean"));
  // One direction.
  o.direction = Direction::kRefToDist;
  const MetricResult ab = compute_pointssim(a, b, o);
  EXPECT_FALSE(ab.dist_to_ref.has_value());
  EXPECT_EQ(ab.score, r.ref_to_dist->score);
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(Pointssim, BadInputIsOneLineNamingTheFile) {
  PointssimOptions o;
  o.fit = PointssimFit::kKnn;
  o.fit_size = 12;
  const ColoredCloud a = read("sphere_2k_ref.ply");
  ColoredCloud small;
  for (int i = 0; i < 5; ++i) {
    small.positions.push_back({double(i), double(i * i), 0.5 * i});
    small.colors.push_back({0.5, 0.5, 0.5});
  }
  o.neighbours = 3;
  std::string m = message_of([&] { compute_pointssim(a, small, o, "a.ply", "small.ply"); });
  EXPECT_EQ(m.rfind("small.ply: 5 distinct points; pointssim needs at least 12", 0), 0u) << m;
  EXPECT_THROW(compute_pointssim(a, small, o, "a.ply", "small.ply"), NumericError);
  ColoredCloud plain = a;
  plain.colors.clear();
  o.attributes = {PointssimAttribute::kColor};
  m = message_of([&] { compute_pointssim(a, plain, o, "a.ply", "plain.ply"); });
  EXPECT_EQ(m.rfind("plain.ply: no colours", 0), 0u) << m;
  EXPECT_EQ(m.find('\n'), std::string::npos);
  EXPECT_THROW(compute_pointssim(a, plain, o, "a.ply", "plain.ply"), FormatError);
  // The reference's default radius on a unit sphere: round(0.02) = 0.
  o.fit = PointssimFit::kDefaultRadius;
  o.attributes = {};
  m = message_of([&] { compute_pointssim(a, a, o); });
  EXPECT_NE(m.find("default fit radius"), std::string::npos) << m;
  ColoredCloud broken = a;
  broken.positions[3][1] = std::numeric_limits<double>::quiet_NaN();
  m = message_of([&] { compute_pointssim(broken, a, o, "broken.ply", "a.ply"); });
  EXPECT_EQ(m.rfind("broken.ply: point 3", 0), 0u) << m;
  EXPECT_THROW(parse_pointssim_estimators("var,nope", "estimators"), std::invalid_argument);
}

TEST(Pointssim, DefaultRadiusIsOnePercentOfTheReferencesExtentRounded) {
  // A 300 x 300 grid: extent 299 -> radius round(2.99) = 3, the voxel case's explicit radius.
  ColoredCloud grid;
  for (int x = 0; x < 300; x += 1) {
    for (int y = 0; y < 300; y += 7)
      grid.positions.push_back({double(x), double(y), 0.1 * (x % 3)});
  }
  PointssimOptions o;
  o.attributes = {PointssimAttribute::kCurv};
  const MetricResult r = compute_pointssim(grid, grid, o);
  EXPECT_EQ(r.details.at("fit").at("method"), "radius");
  EXPECT_EQ(r.details.at("fit").at("size").get<double>(), 3.0);
}

// Internal rules.

TEST(PointssimRules, NeighboursComeByDistanceThenLowerRow) {
  // Rows of a sorted cloud; from (0, 0, 0) four points at distance 1 and one at 2.
  const std::vector<Vec3> points{{-1, 0, 0}, {0, -1, 0}, {0, 0, 0},
                                 {0, 1, 0},  {1, 0, 0},  {2, 0, 0}};
  const detail::OrderedSearch search(points, 1);
  std::vector<detail::Neighbour> nb;
  search.knn(points[2], 3, nb);
  ASSERT_EQ(nb.size(), 3u);
  EXPECT_EQ(nb[0].index, 2u);
  EXPECT_EQ(nb[1].index, 0u);
  EXPECT_EQ(nb[2].index, 1u);
  search.knn({0.5, 0, 0}, 1, nb);  // (0,0,0) and (1,0,0) tie: the lower row
  EXPECT_EQ(nb[0].index, 2u);
  search.within(points[2], 1.0, nb);  // inclusive
  ASSERT_EQ(nb.size(), 5u);
  EXPECT_EQ(nb[4].index, 4u);
}

TEST(PointssimRules, FusionSortsRowsAndRoundsColoursHalfAwayFromZero) {
  ColoredCloud c;
  c.positions = {{1, 0, 0}, {0, 0, 0}, {1, 0, 0}, {0, 0, 0}};
  c.colors = {{1 / 255.0, 0, 0}, {10 / 255.0, 0, 1}, {2 / 255.0, 0, 0}, {11 / 255.0, 1, 1}};
  const detail::SsimCloud s = detail::prepare_cloud(c, true, "c");
  ASSERT_EQ(s.points.size(), 2u);
  EXPECT_EQ(s.points[0], (Vec3{0, 0, 0}));
  EXPECT_EQ(s.colours[0], (std::array<std::uint8_t, 3>{11, 128, 255}));  // 10.5 -> 11, 127.5 -> 128
  EXPECT_EQ(s.colours[1], (std::array<std::uint8_t, 3>{2, 0, 0}));       // 1.5 -> 2
  EXPECT_EQ(s.of_input, (std::vector<std::uint32_t>{1, 0, 1, 0}));
  EXPECT_EQ(s.duplicates, 2u);
}

TEST(PointssimRules, EstimatorsOnHandMadeValues) {
  std::vector<double> scratch;
  const double q[6] = {4, 1, 3, 2, 6, 5};
  auto est = [&](PointssimEstimator e, std::size_t m) {
    return detail::estimate(e, q, m, scratch);
  };
  EXPECT_DOUBLE_EQ(est(PointssimEstimator::kMean, 6), 3.5);
  EXPECT_DOUBLE_EQ(est(PointssimEstimator::kVar, 6), 3.5);  // 17.5 / 5
  EXPECT_DOUBLE_EQ(est(PointssimEstimator::kStd, 6), std::sqrt(3.5));
  EXPECT_DOUBLE_EQ(est(PointssimEstimator::kMeanAd, 6), 1.5);
  EXPECT_DOUBLE_EQ(est(PointssimEstimator::kMedianAd, 6), 1.5);  // |q - 3.5|: .5 .5 1.5 1.5 2.5 2.5
  EXPECT_DOUBLE_EQ(est(PointssimEstimator::kCov, 6), std::sqrt(3.5) / 3.5);
  // MATLAB's quantile on 1..6: p = 0.25 -> position 2 -> 2; p = 0.75 -> 5 -> 5.
  EXPECT_DOUBLE_EQ(est(PointssimEstimator::kQcd, 6), 3.0 / 7.0);
  // On 4 1 3 2 3: positions 1.75 and 4.25 of 1 2 3 3 4 -> 1.75 and 3.25.
  const double r[5] = {4, 1, 3, 2, 3};
  EXPECT_DOUBLE_EQ(detail::estimate(PointssimEstimator::kQcd, r, 5, scratch), 1.5 / 5.0);
  // A NaN value: mean and median NaN, the quartiles over the other values.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double s[4] = {1, nan, 2, 3};
  EXPECT_TRUE(std::isnan(detail::estimate(PointssimEstimator::kMedianAd, s, 4, scratch)));
  EXPECT_DOUBLE_EQ(detail::estimate(PointssimEstimator::kQcd, s, 4, scratch), (2.75 - 1.25) / 4.0);
}

}  // namespace
}  // namespace qm3d::pointcloud
