// The clip tests' shortcut (vec3_ops.h, far_end_clearly_inside) changes nothing: on edges drawn
// around the sphere, near it, tiny and long, both clip tests give the answer and the clipped
// vector, bit for bit, of the full quadratic alone (written out here as the tests stood before).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "curvature.h"
#include "neighbourhood.h"
#include "vec3_ops.h"

namespace qm3d::mesh::detail {
namespace {

bool full_clip(const Vec3& o, double r, const Vec3& p, Vec3& v, bool cmdm_variant) {
  const Vec3 w = sub(p, o);
  const double a = dot(v, v);
  if (!cmdm_variant && std::fabs(a) < kClipEpsilon) return false;
  const double b = 2.0 * dot(v, w);
  const double c = dot(w, w) - r * r;
  const double delta = b * b - 4. * a * c;
  if (cmdm_variant && a == 0) return true;
  if (delta < 0.) return true;
  double t = (-b + std::sqrt(delta)) / (2.0 * a);
  if (cmdm_variant && t < 0.0) return true;
  if (t >= 1.) return false;
  if (cmdm_variant && t < 1e-16) t = 0.01;
  v = scale(v, t);
  return true;
}

Vec3 random_direction(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  const Vec3 d{g(rng), g(rng), g(rng)};
  return scale(d, 1.0 / norm(d));
}

TEST(SphereClip, ShortcutGivesTheFullTestsAnswerBitForBit) {
  std::mt19937_64 rng(45);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vec3 o{0.3, -1.7, 2.1};
  std::size_t shortcut_cases = 0;
  for (int i = 0; i < 200000; ++i) {
    const double r = std::pow(10.0, -9 + 10 * u(rng));
    // p inside or just around the sphere; the far end anywhere from well inside to outside,
    // with some ends within 1e-4..1e-12 of the sphere and some edges down to 1e-9 r.
    const Vec3 p = add(o, scale(random_direction(rng), r * std::pow(u(rng), 0.3) * 1.0001));
    const double end_radius =
        i % 4 == 0 ? r * (1 - std::pow(10.0, -4 - 8 * u(rng))) : r * 1.2 * std::pow(u(rng), 0.5);
    Vec3 end = add(o, scale(random_direction(rng), end_radius));
    if (i % 7 == 0) end = add(p, scale(random_direction(rng), r * std::pow(10.0, -9 * u(rng))));
    const Vec3 edge = sub(end, p);
    if (far_end_clearly_inside(sub(p, o), edge, dot(edge, edge), r)) ++shortcut_cases;
    for (bool cmdm : {false, true}) {
      Vec3 got = edge, want = edge;
      const bool g =
          cmdm ? sphere_clip_vector_cmdm(o, r, p, got) : sphere_clip_vector(o, r, p, got);
      const bool f = full_clip(o, r, p, want, cmdm);
      ASSERT_EQ(g, f) << "case " << i << (cmdm ? " (CMDM)" : "");
      for (int k = 0; k < 3; ++k) ASSERT_EQ(got[k], want[k]) << "case " << i;
    }
  }
  EXPECT_GT(shortcut_cases, 20000u);  // the shortcut is exercised
}

}  // namespace
}  // namespace qm3d::mesh::detail
