#include "qm3d/common/types.h"

#include <algorithm>

#include "qm3d/common/error.h"

namespace qm3d {

double BoundingBox::longest_side() const {
  return std::max({max[0] - min[0], max[1] - min[1], max[2] - min[2]});
}

BoundingBox bounding_box(const std::vector<Vec3>& positions) {
  return bounding_box(positions.data(), positions.data() + positions.size());
}

BoundingBox bounding_box(const Vec3* begin, const Vec3* end) {
  if (begin == end) throw NumericError("bounding box of an empty point set");
  BoundingBox box{*begin, *begin};
  for (const Vec3* it = begin; it != end; ++it) {
    const Vec3& p = *it;
    for (int k = 0; k < 3; ++k) {
      box.min[k] = std::min(box.min[k], p[k]);
      box.max[k] = std::max(box.max[k], p[k]);
    }
  }
  return box;
}

}  // namespace qm3d
