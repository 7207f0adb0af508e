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
  // glm::mix(x, y, a) as GLM 0.9.9 computes it (detail/func_common.inl compute_mix_scalar):
  // x (1 - a) + y a, in float. Not x + a (y - x), which rounds differently: on mmetric's textured
  // basketball frame that form moved a few hundred pixels per view by one 8-bit level (IBSM
  // colour MSEs off in the 6th digit, tests/render/ibsm_textured_reference_test.cpp).
  const auto mix = [](const Float3& x, const Float3& y, float a) {
    const float keep = 1.0f - a;
    return Float3{x[0] * keep + y[0] * a, x[1] * keep + y[1] * a, x[2] * keep + y[2] * a};
  };
  return mix(mix(tl, tr, fx), mix(bl, br, fx), fy);
}

}  // namespace qm3d::mesh
