// Small arithmetic on Vec3 used by the mesh walks. Internal.
#pragma once

#include <cmath>

#include "qm3d/common/types.h"

namespace qm3d::mesh::detail {

inline Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Vec3 scale(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline double distance(const Vec3& a, const Vec3& b) { return norm(sub(a, b)); }
inline bool has_nan(const Vec3& a) {
  return std::isnan(a[0]) || std::isnan(a[1]) || std::isnan(a[2]);
}

// far_end_clearly_inside's margins (chosen with room to spare; see its comment).
constexpr double kInsideMargin = 1e-4;        // |w + v|^2 <= (1 - 1e-4) r^2
constexpr double kShortestEdgeRatio = 1e-12;  // |v|^2 >= 1e-12 r^2, i.e. |v| >= 1e-6 r

/// A shortcut before MEPP2's sphere clip tests (sphere_clip_vector and its CMDM variant), which
/// return "not clipped" when the computed t = (-b + sqrt(b^2 - 4ac)) / 2a, the far root of
/// |w + t v|^2 = r^2 (w = p - o, a = v.v, b = 2 v.w, c = w.w - r^2), is >= 1. True only where
/// that computed t is certainly >= 1, so the callers skip the square root and division and
/// return what the full test returns. Why it is certain: with |w + v|^2 - r^2 <= -m r^2
/// (m = kInsideMargin), |w|^2 <= 2 r^2 and so |v| <= (1 + sqrt 2) r, the exact far root is
/// t* >= 1 + m / 7 and b^2 - 4ac >= 4 a m r^2 > 0; the rounding of a, b, c, the discriminant,
/// its square root and the quotient moves t by at most about 1300 eps r / |v| (eps = 2^-52),
/// below 2e-7 when |v| >= 1e-6 r, far less than m / 7 = 1.4e-5. `a` is v.v as the caller
/// computed it; NaN anywhere gives false.
inline bool far_end_clearly_inside(const Vec3& w, const Vec3& v, double a, double r) {
  const double r2 = r * r;
  const Vec3 e = add(w, v);
  return a >= kShortestEdgeRatio * r2 && dot(w, w) <= 2.0 * r2 &&
         dot(e, e) - r2 <= -kInsideMargin * r2 && r2 > 0;
}

}  // namespace qm3d::mesh::detail
