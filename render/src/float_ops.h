// Single-precision vector and matrix operations, each evaluated in the order GLM 0.9.9.8 uses
// (the library mmetric 1.1.7 renders with: MPEGGroup/mpeg-pcc-mmetric @ 5faa660,
// dependencies/glm). The rasteriser reproduces mmetric's pixels bit for bit, so every sum here
// keeps GLM's association and the sources that include this header are compiled with
// -ffp-contract=off (no fused multiply-adds: render/CMakeLists.txt).
#pragma once

#include <cmath>

namespace qm3d::render::detail {

struct F3 {
  float x = 0, y = 0, z = 0;
};
struct F4 {
  float x = 0, y = 0, z = 0, w = 0;
};
/// Column-major, as GLM: c[j] is column j.
struct M4 {
  F4 c[4];
};

inline F3 operator+(F3 a, F3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline F3 operator-(F3 a, F3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline F3 operator*(F3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline F3 operator*(float s, F3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline F4 operator+(F4 a, F4 b) { return {a.x + b.x, a.y + b.y, a.z + b.z, a.w + b.w}; }
inline F4 operator*(F4 a, float s) { return {a.x * s, a.y * s, a.z * s, a.w * s}; }

/// GLM's compute_dot<vec3>: (x + y) + z of the products.
inline float dot(F3 a, F3 b) {
  const float tx = a.x * b.x, ty = a.y * b.y, tz = a.z * b.z;
  return tx + ty + tz;
}
inline F3 cross(F3 a, F3 b) {
  return {a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y};
}
inline float length(F3 v) { return std::sqrt(dot(v, v)); }
/// GLM: v * inversesqrt(dot(v, v)), inversesqrt = 1 / sqrt.
inline F3 normalize(F3 v) { return v * (1.0f / std::sqrt(dot(v, v))); }

inline M4 identity() {
  M4 m;
  m.c[0].x = m.c[1].y = m.c[2].z = m.c[3].w = 1.0f;
  return m;
}
/// GLM's mat4 * vec4: (m0 v.x + m1 v.y) + (m2 v.z + m3 v.w).
inline F4 mul(const M4& m, F4 v) {
  const F4 add0 = m.c[0] * v.x + m.c[1] * v.y;
  const F4 add1 = m.c[2] * v.z + m.c[3] * v.w;
  return add0 + add1;
}
/// GLM's mat4 * mat4: each column ((a0 b.x + a1 b.y) + a2 b.z) + a3 b.w.
inline M4 mul(const M4& a, const M4& b) {
  M4 r;
  for (int j = 0; j < 4; ++j) {
    const F4 s = b.c[j];
    r.c[j] = a.c[0] * s.x + a.c[1] * s.y + a.c[2] * s.z + a.c[3] * s.w;
  }
  return r;
}
/// GLM's translate(identity, v) and scale(identity, v).
inline M4 translation(F3 v) {
  const M4 m = identity();
  M4 r = m;
  r.c[3] = m.c[0] * v.x + m.c[1] * v.y + m.c[2] * v.z + m.c[3];
  return r;
}
inline M4 scaling(F3 v) {
  const M4 m = identity();
  M4 r;
  r.c[0] = m.c[0] * v.x;
  r.c[1] = m.c[1] * v.y;
  r.c[2] = m.c[2] * v.z;
  r.c[3] = m.c[3];
  return r;
}
/// GLM's lookAtRH.
inline M4 look_at(F3 eye, F3 center, F3 up) {
  const F3 f = normalize(center - eye);
  const F3 s = normalize(cross(f, up));
  const F3 u = cross(s, f);
  M4 r = identity();
  r.c[0].x = s.x;
  r.c[1].x = s.y;
  r.c[2].x = s.z;
  r.c[0].y = u.x;
  r.c[1].y = u.y;
  r.c[2].y = u.z;
  r.c[0].z = -f.x;
  r.c[1].z = -f.y;
  r.c[2].z = -f.z;
  r.c[3].x = -dot(s, eye);
  r.c[3].y = -dot(u, eye);
  r.c[3].z = dot(f, eye);
  return r;
}
/// GLM's orthoRH_NO (its default clip control).
inline M4 ortho(float left, float right, float bottom, float top, float z_near, float z_far) {
  M4 r = identity();
  r.c[0].x = 2.0f / (right - left);
  r.c[1].y = 2.0f / (top - bottom);
  r.c[2].z = -2.0f / (z_far - z_near);
  r.c[3].x = -(right + left) / (right - left);
  r.c[3].y = -(top + bottom) / (top - bottom);
  r.c[3].z = -(z_far + z_near) / (z_far - z_near);
  return r;
}
/// GLM's rotate(identity, angle, axis) (ext/matrix_transform.inl).
inline M4 rotation(float angle_rad, F3 v) {
  const float c = std::cos(angle_rad);
  const float s = std::sin(angle_rad);
  const F3 axis = normalize(v);
  const F3 temp = (1.0f - c) * axis;
  float rot[3][3];
  rot[0][0] = c + temp.x * axis.x;
  rot[0][1] = temp.x * axis.y + s * axis.z;
  rot[0][2] = temp.x * axis.z - s * axis.y;
  rot[1][0] = temp.y * axis.x - s * axis.z;
  rot[1][1] = c + temp.y * axis.y;
  rot[1][2] = temp.y * axis.z + s * axis.x;
  rot[2][0] = temp.z * axis.x + s * axis.y;
  rot[2][1] = temp.z * axis.y - s * axis.x;
  rot[2][2] = c + temp.z * axis.z;
  const M4 m = identity();
  M4 r;
  for (int j = 0; j < 3; ++j) r.c[j] = m.c[0] * rot[j][0] + m.c[1] * rot[j][1] + m.c[2] * rot[j][2];
  r.c[3] = m.c[3];
  return r;
}

}  // namespace qm3d::render::detail
