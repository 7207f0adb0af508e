#include "qm3d/common/grid_samples.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <optional>
#include <sstream>

#include "qm3d/common/reading.h"

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

std::string float32_precision_warning(const Vec3& min, const Vec3& max, double spacing,
                                      const std::string& spacing_name, const std::string& name,
                                      const std::string& tool) {
  double largest = 0, extent = 0;
  for (int k = 0; k < 3; ++k) {
    largest = std::max({largest, std::fabs(min[k]), std::fabs(max[k])});
    extent = std::max(extent, max[k] - min[k]);
  }
  const std::optional<double> step = large_float32_step(largest, spacing);
  if (!step) return {};
  std::ostringstream w;
  w.precision(3);
  w << name << ": coordinates reach " << largest << ", far from the origin for the content's size ("
    << extent << "): " << tool << " computes in float32, whose step there (" << *step
    << ") is more than 1/8 of the " << spacing_name << " (" << spacing
    << "), so the values lose precision as in " << tool
    << "; move the content near the origin (subtract its centre from both inputs) for precise "
       "values";
  return w.str();
}

}  // namespace qm3d
