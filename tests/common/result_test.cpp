// The one result type and its writers (qm3d/common/result.h, result_io.h).
#include "qm3d/common/result.h"

#include <gtest/gtest.h>

#include "qm3d/common/result_io.h"
#include "qm3d/study/batch_row.h"

namespace qm3d {
namespace {

MetricResult two_directions() {
  MetricResult r;
  r.metric = "cmdm";
  r.feature_names = feature_names("f");
  r.dist_to_ref = DirectionResult{0.25, {0, 0.5, 0, 0, 0, 0, 0, 0}, 2.0, {}};
  r.ref_to_dist = DirectionResult{0.75, {0, 1.5, 0, 0, 0, 0, 0, 0}, 3.0, {}};
  r.provenance.reference = "ref, with comma.obj";
  r.provenance.distorted = "dist.obj";
  r.provenance.options = {{"direction", "symmetric"}};
  combine_directions(r);
  return r;
}

TEST(Result, DirectionsCombineAndNameThemselves) {
  MetricResult r = two_directions();
  EXPECT_EQ(r.score, 0.5);
  EXPECT_EQ(r.direction(), Direction::kSymmetric);
  EXPECT_EQ(&r.any_direction(true), &*r.dist_to_ref);
  EXPECT_EQ(&r.any_direction(false), &*r.ref_to_dist);
  r.dist_to_ref.reset();
  combine_directions(r);
  EXPECT_EQ(r.score, 0.75);
  EXPECT_EQ(r.direction(), Direction::kRefToDist);
  r.ref_to_dist.reset();
  EXPECT_THROW(combine_directions(r), std::logic_error);
  for (Direction d : {Direction::kSymmetric, Direction::kDistToRef, Direction::kRefToDist}) {
    EXPECT_EQ(parse_direction(direction_name(d)), d);
  }
  EXPECT_THROW(parse_direction("both"), std::invalid_argument);
  EXPECT_EQ(feature_names("F").back(), "F8");
}

TEST(ResultIo, JsonHasEveryDirectionAndTheSingleOneAtTheTop) {
  MetricResult r = two_directions();
  nlohmann::json j = to_json(r);
  EXPECT_EQ(j["score"], 0.5);
  EXPECT_EQ(j["directions"]["dist_to_ref"]["features"]["f2"], 0.5);
  EXPECT_EQ(j["directions"]["ref_to_dist"]["box_size"], 3.0);
  EXPECT_EQ(j["directions"]["ref_to_dist"]["bbox_max_side"], 3.0);  // the former name, kept
  EXPECT_FALSE(j.contains("features"));  // two directions: none is "the" one
  EXPECT_EQ(j["options"]["direction"], "symmetric");
  r.dist_to_ref.reset();
  combine_directions(r);
  j = to_json(r);
  EXPECT_EQ(j["features"]["f2"], 1.5);
  EXPECT_EQ(j["box_size"], 3.0);
  EXPECT_TRUE(j["directions"].contains("ref_to_dist"));
  r.score = std::nan("");
  EXPECT_TRUE(to_json(r)["score"].is_null());
}

TEST(ResultIo, CsvRowsHaveTheHeadersColumnsAndQuoteFields) {
  using study::csv_error_row, study::csv_header, study::csv_row;
  const MetricResult r = two_directions();
  const auto header = csv_split(csv_header());
  const auto row = csv_split(csv_row(r));
  ASSERT_EQ(row.size(), header.size());
  EXPECT_EQ(row[0], "ref, with comma.obj");
  EXPECT_EQ(row[3], "0.5");
  EXPECT_EQ(row[4], "ok");
  EXPECT_EQ(csv_split(csv_error_row("a", "b", "pcqm", "bad \"x\"")).size(), header.size());
  EXPECT_EQ(csv_split(csv_error_row("a", "b", "pcqm", "bad \"x\""))[5], "bad \"x\"");
  EXPECT_EQ(format_double(0.1), "0.1");
  EXPECT_EQ(std::stod(format_double(1.0 / 3)), 1.0 / 3);
}

TEST(ResultIo, TextLineNamesTheDirections) {
  MetricResult r = two_directions();
  EXPECT_EQ(text_line(r), "CMDM = 0.5  (dist\u2192ref 0.25, ref\u2192dist 0.75)");
  r.dist_to_ref.reset();
  combine_directions(r);
  EXPECT_EQ(text_line(r), "CMDM = 0.75  (ref\u2192dist)");
  const nlohmann::json both = compare_json({two_directions(), r});
  EXPECT_EQ(both["metric"], "compare");
  EXPECT_EQ(both["reference"], "ref, with comma.obj");
}

}  // namespace
}  // namespace qm3d
