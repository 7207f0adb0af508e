#include "qm3d/common/grid_samples.h"

#include <algorithm>
#include <cfloat>
#include <cmath>

namespace qm3d {

namespace {

template <typename Point>
FloatBox box_of(const std::vector<Point>& positions) {
  FloatBox b{{FLT_MAX, FLT_MAX, FLT_MAX}, {-FLT_MAX, -FLT_MAX, -FLT_MAX}};
  for (const Point& p : positions) {
    for (int k = 0; k < 3; ++k) {
      const float f = static_cast<float>(p[k]);
      b.min[k] = std::fmin(f, b.min[k]);
      b.max[k] = std::fmax(f, b.max[k]);
    }
  }
  return b;
}

}  // namespace

FloatBox vertex_box(const std::vector<Vec3>& positions) { return box_of(positions); }
FloatBox vertex_box(const std::vector<Float3>& positions) { return box_of(positions); }

FloatBox union_box(const FloatBox& a, const FloatBox& b) {
  FloatBox u;
  for (int k = 0; k < 3; ++k) {
    u.min[k] = std::min(a.min[k], b.min[k]);
    u.max[k] = std::max(a.max[k], b.max[k]);
  }
  return u;
}

}  // namespace qm3d
