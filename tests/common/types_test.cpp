#include "qm3d/common/types.h"

#include <gtest/gtest.h>

#include "qm3d/common/error.h"

namespace qm3d {
namespace {

TEST(Types, BoundingBoxLongestSide) {
  const auto box = bounding_box({{0, 0, 0}, {1, -2, 0.5}, {-1, 1, 0}});
  EXPECT_DOUBLE_EQ(box.longest_side(), 3.0);  // y: -2 .. 1
  EXPECT_THROW(bounding_box({}), NumericError);
}

TEST(Types, VertexCloudKeepsPositionsAndColours) {
  ColoredMesh m{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 1, 2}}};
  const ColoredCloud c = vertex_cloud(m);
  EXPECT_EQ(c.size(), 3u);
  EXPECT_EQ(c.colors[2].b, 1.0);
}

}  // namespace
}  // namespace qm3d
