// The view writer of ibsm --save-views (png_bytes): a view comes back from its PNG pixel for
// pixel (rows bottom first in the view, top first in the file); an empty view, which PNG cannot
// hold, is refused (fuzz_views found the 0x0 PNG no reader opens).
#include <gtest/gtest.h>
#include <stb/stb_image.h>

#include <cstdint>
#include <stdexcept>
#include <vector>

#include "qm3d/render/ibsm.h"
#include "qm3d/render/raster.h"

namespace qm3d::render {
namespace {

View view(int width, int height) {
  View v;
  v.width = width;
  v.height = height;
  v.rgba.resize(static_cast<std::size_t>(width) * height * 4);
  for (std::size_t i = 0; i < v.rgba.size(); ++i) v.rgba[i] = static_cast<std::uint8_t>(i * 37);
  return v;
}

TEST(ViewWriter, APngHoldsTheViewTopRowFirst) {
  const View v = view(3, 2);
  const std::vector<std::uint8_t> png = png_bytes(v);
  int w = 0, h = 0, channels = 0;
  stbi_uc* pixels =
      stbi_load_from_memory(png.data(), static_cast<int>(png.size()), &w, &h, &channels, 4);
  ASSERT_NE(pixels, nullptr);
  ASSERT_EQ(w, 3);
  ASSERT_EQ(h, 2);
  const std::vector<std::uint8_t> got(pixels, pixels + 24);
  stbi_image_free(pixels);
  std::vector<std::uint8_t> expected(v.rgba.begin() + 12, v.rgba.end());  // the top row
  expected.insert(expected.end(), v.rgba.begin(), v.rgba.begin() + 12);
  EXPECT_EQ(got, expected);
}

TEST(ViewWriter, AnEmptyOrInconsistentViewIsRefused) {
  EXPECT_THROW(png_bytes(view(0, 0)), std::invalid_argument);
  EXPECT_THROW(png_bytes(view(0, 5)), std::invalid_argument);
  EXPECT_THROW(png_bytes(view(4, 0)), std::invalid_argument);
  View short_of_bytes = view(2, 2);
  short_of_bytes.rgba.pop_back();
  EXPECT_THROW(png_bytes(short_of_bytes), std::invalid_argument);
}

}  // namespace
}  // namespace qm3d::render
