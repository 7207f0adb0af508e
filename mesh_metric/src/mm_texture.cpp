// mmetric 1.1.7's texel lookups (MPEGGroup/mpeg-pcc-mmetric @ 5faa660, source/lib/include/
// mmImage.h `texture2D`, `texture2D_bilinear`), shared by its grid sampling (grid_sampling.cpp)
// and its software renderer (render/). Float32 in glm's order; compiled with -ffp-contract=off.
#include <algorithm>
#include <cmath>

#include "qm3d/mesh/texture.h"

namespace qm3d::mesh {
namespace {

/// Texel (x, y) with y counted from the bottom row, both clamped to the image.
Float3 texel(const TextureImage& img, int x, int y) {
  x = std::min(std::max(x, 0), img.width - 1);
  y = img.height - 1 - std::min(std::max(y, 0), img.height - 1);
  const Rgb& c = img.texels[static_cast<std::size_t>(y) * img.width + x];
  return {mm_channel_255(c.r), mm_channel_255(c.g), mm_channel_255(c.b)};
}

}  // namespace

Float3 mm_texture_lookup(const TextureImage& img, float u, float v, bool bilinear) {
  if (!bilinear) {
    return texel(img, static_cast<int>(u * static_cast<float>(img.width)),
                 static_cast<int>(v * static_cast<float>(img.height)));
  }
  const float px = u * static_cast<float>(img.width) - 0.5f;
  const float py = v * static_cast<float>(img.height) - 0.5f;
  const float fx0 = std::floor(px), fy0 = std::floor(py);
  const int x0 = static_cast<int>(fx0), y0 = static_cast<int>(fy0);
  const float fx = px - fx0, fy = py - fy0;  // glm::fract
  const Float3 tl = texel(img, x0, y0), tr = texel(img, x0 + 1, y0);
  const Float3 bl = texel(img, x0, y0 + 1), br = texel(img, x0 + 1, y0 + 1);
  const auto mix = [](const Float3& a, const Float3& b, float t) {  // glm::mix: a + t (b - a)
    return Float3{a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])};
  };
  return mix(mix(tl, tr, fx), mix(bl, br, fx), fy);
}

}  // namespace qm3d::mesh
