// The rasteriser (qm3d/render/raster.h). Rules and their places in mmetric 1.1.7
// (MPEGGroup/mpeg-pcc-mmetric @ 5faa660), reimplemented here:
// - canonical order: source/lib/include/mmModel.h `reorder(..., "oriented", ...)`;
// - bounding box, sphere, camera: mmCompare.cpp `ibsm`, mmRendererSw.cpp `RendererSw::render`;
// - coverage, depth, colour: mmRendererSw.cpp `rasterize` with `ShaderCpv` / `ShaderRed`;
// - views: mmCompare.cpp `fibonacciSphere`.
// Every float expression keeps mmetric's (GLM's) order of operations (float_ops.h).
#include "qm3d/render/raster.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <nanoflann.hpp>
#include <stdexcept>
#include <string>

#include "float_ops.h"
#include "qm3d/common/error.h"
#include "qm3d/common/large_arrays.h"
#include "raster_bands.h"

namespace qm3d::render {

using detail::F3;
using detail::F4;
using detail::M4;

namespace {

F3 f3(const Float3& a) { return {a[0], a[1], a[2]}; }
Float3 arr(F3 a) { return {a.x, a.y, a.z}; }

struct VertexKey {
  Float3 pos;
  std::array<float, 2> uv{0, 0};
  Float3 col{0, 0, 0};
};
/// mmModel.h CompareVertex: lexicographic on position, then UV, then colour (float <, so
/// -0 == +0).
bool key_less(const VertexKey& a, const VertexKey& b) {
  for (int k = 0; k < 3; ++k) {
    if (a.pos[k] != b.pos[k]) return a.pos[k] < b.pos[k];
  }
  for (int k = 0; k < 2; ++k) {
    if (a.uv[k] != b.uv[k]) return a.uv[k] < b.uv[k];
  }
  for (int k = 0; k < 3; ++k) {
    if (a.col[k] != b.col[k]) return a.col[k] < b.col[k];
  }
  return false;
}

/// Rotates a face so that its smallest index comes first, keeping its orientation (mmetric's
/// "oriented" rule, ties included).
Triangle rotate_to_smallest(Triangle t) {
  if (t[1] < t[0] && t[1] <= t[2]) return {t[1], t[2], t[0]};
  if (t[2] <= t[0] && t[2] < t[1]) return {t[2], t[0], t[1]};
  return t;
}

/// The unique keys of the faces' corners in sorted order and each corner's rank among them
/// (mmetric's ModelBuilder then sorted map: equal keys are one vertex).
std::vector<VertexKey> sorted_vertices(const std::vector<VertexKey>& corner_keys,
                                       std::vector<std::uint32_t>& rank_of_corner) {
  std::vector<std::uint32_t> order(corner_keys.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return key_less(corner_keys[a], corner_keys[b]);
  });
  std::vector<VertexKey> unique;
  rank_of_corner.assign(corner_keys.size(), 0);
  for (std::uint32_t c : order) {
    if (unique.empty() || key_less(unique.back(), corner_keys[c])) unique.push_back(corner_keys[c]);
    rank_of_corner[c] = static_cast<std::uint32_t>(unique.size() - 1);
  }
  return unique;
}

Float3 float_position(const Vec3& p) {
  return {static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])};
}

/// Unit vertex normals: area-weighted face normals summed (in double), normalised.
std::vector<Float3> vertex_normals(const std::vector<Float3>& positions,
                                   const std::vector<Triangle>& triangles) {
  std::vector<Vec3> sum(positions.size(), Vec3{0, 0, 0});
  for (const Triangle& t : triangles) {
    const Float3 &a = positions[t[0]], &b = positions[t[1]], &c = positions[t[2]];
    const double e1[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
    const double e2[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
    const Vec3 n{e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                 e1[0] * e2[1] - e1[1] * e2[0]};
    for (std::uint32_t v : t) {
      for (int k = 0; k < 3; ++k) sum[v][k] += n[k];
    }
  }
  std::vector<Float3> out(positions.size(), Float3{0, 0, 0});
  for (std::size_t v = 0; v < sum.size(); ++v) {
    const Vec3& n = sum[v];
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (len > 0) {
      out[v] = {static_cast<float>(n[0] / len), static_cast<float>(n[1] / len),
                static_cast<float>(n[2] / len)};
    }
  }
  return out;
}

/// The canonical model of faces given by their corners' keys (one texture index per face, or
/// none): mmetric's reorder(..., "oriented"): vertices unique and sorted, each face rotated to
/// start at its smallest vertex, faces sorted by (corners, texture) and made unique.
RenderModel canonical_mesh(const std::vector<VertexKey>& corner_keys,
                           const std::vector<std::uint32_t>& face_texture, bool colours,
                           bool textured) {
  std::vector<std::uint32_t> rank;
  const std::vector<VertexKey> unique = sorted_vertices(corner_keys, rank);
  RenderModel out;
  for (const VertexKey& k : unique) {
    out.positions.push_back(k.pos);
    if (colours) out.colors_255.push_back(k.col);
    if (textured) out.uvs.push_back(k.uv);
  }
  const std::size_t faces = corner_keys.size() / 3;
  std::vector<std::array<std::uint32_t, 4>> sorted(faces);
  for (std::size_t f = 0; f < faces; ++f) {
    const Triangle t = rotate_to_smallest({rank[3 * f], rank[3 * f + 1], rank[3 * f + 2]});
    sorted[f] = {t[0], t[1], t[2], face_texture.empty() ? 0u : face_texture[f]};
  }
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  out.triangles.reserve(sorted.size());
  for (const auto& f : sorted) {
    out.triangles.push_back({f[0], f[1], f[2]});
    if (textured) out.triangle_texture.push_back(f[3]);
  }
  out.normals = vertex_normals(out.positions, out.triangles);
  return out;
}

}  // namespace

RenderModel mesh_model(const ColoredMesh& mesh, bool has_colors) {
  if (mesh.triangles.empty()) throw FormatError("mesh has no faces to render");
  has_colors = has_colors && mesh.colors.size() == mesh.positions.size();
  std::vector<VertexKey> corners;
  corners.reserve(3 * mesh.triangles.size());
  for (const Triangle& t : mesh.triangles) {
    for (std::uint32_t v : t) {
      VertexKey k;
      k.pos = float_position(mesh.positions[v]);
      if (has_colors) {
        const Rgb& c = mesh.colors[v];
        k.col = {mesh::mm_channel_255(c.r), mesh::mm_channel_255(c.g), mesh::mm_channel_255(c.b)};
      }
      corners.push_back(k);
    }
  }
  return canonical_mesh(corners, {}, has_colors, false);
}

RenderModel textured_mesh_model(const mesh::TexturedMesh& mesh) {
  const ColoredMesh& m = mesh.file.mesh;
  if (m.triangles.empty()) throw FormatError("mesh has no faces to render");
  std::vector<VertexKey> corners;
  corners.reserve(3 * m.triangles.size());
  for (std::size_t f = 0; f < m.triangles.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      VertexKey key;
      key.pos = float_position(m.positions[m.triangles[f][k]]);
      const mesh::Uv& uv = mesh.uvs[mesh.triangle_uvs[f][k]];
      key.uv = {static_cast<float>(uv[0]), static_cast<float>(uv[1])};
      corners.push_back(key);
    }
  }
  RenderModel out = canonical_mesh(corners, mesh.triangle_texture, false, true);
  out.textures = std::make_shared<const std::vector<mesh::TextureImage>>(mesh.textures);
  return out;
}

namespace {

struct PointsAdaptor {
  const std::vector<Float3>& points;
  std::size_t kdtree_get_point_count() const { return points.size(); }
  float kdtree_get_pt(std::size_t i, std::size_t d) const { return points[i][d]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};
using PointsTree = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<float, PointsAdaptor>, PointsAdaptor, 3, std::uint32_t>;

/// The median distance of a point to its nearest point at a distance > 0, over an evenly
/// spaced subset of the points; 0 when no point has such a neighbour.
double median_spacing(const std::vector<Float3>& points) {
  const PointsAdaptor adaptor{points};
  const PointsTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  const std::size_t step = std::max<std::size_t>(1, (points.size() + kSpacingSamples - 1) /
                                                        kSpacingSamples);
  constexpr std::size_t kNeighbours = 8;  // enough to pass a few coincident points
  std::vector<double> spacing;
  for (std::size_t i = 0; i < points.size(); i += step) {
    std::uint32_t index[kNeighbours];
    float dist2[kNeighbours];
    const std::size_t n = tree.knnSearch(points[i].data(), kNeighbours, index, dist2);
    for (std::size_t k = 0; k < n; ++k) {
      if (dist2[k] > 0) {
        spacing.push_back(std::sqrt(static_cast<double>(dist2[k])));
        break;
      }
    }
  }
  if (spacing.empty()) return 0;
  auto mid = spacing.begin() + static_cast<std::ptrdiff_t>(spacing.size() / 2);
  std::nth_element(spacing.begin(), mid, spacing.end());
  return *mid;
}

}  // namespace

RenderModel cloud_model(const ColoredCloud& cloud, const SplatOptions& options) {
  if (cloud.positions.empty()) throw FormatError("point cloud has no points to render");
  std::vector<VertexKey> keys(cloud.positions.size());
  const bool has_colors = cloud.colors.size() == cloud.positions.size();
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const Vec3& p = cloud.positions[i];
    keys[i].pos = {static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])};
    if (has_colors) {
      const Rgb& c = cloud.colors[i];
      keys[i].col = {mesh::mm_channel_255(c.r), mesh::mm_channel_255(c.g), mesh::mm_channel_255(c.b)};
    }
  }
  std::sort(keys.begin(), keys.end(), key_less);
  keys.erase(std::unique(keys.begin(), keys.end(),
                         [](const VertexKey& a, const VertexKey& b) {
                           return !key_less(a, b) && !key_less(b, a);
                         }),
             keys.end());
  RenderModel out;
  for (const VertexKey& k : keys) {
    out.positions.push_back(k.pos);
    if (has_colors) out.colors_255.push_back(k.col);
  }
  double size = options.size;
  if (size <= 0) size = kAutoSplatFactor * median_spacing(out.positions);
  if (!(size > 0) || !std::isfinite(size)) {
    throw FormatError("point cloud: no two distinct points, so no splat size (give one)");
  }
  out.splat_size = static_cast<float>(size);
  out.splat_shape = options.shape;
  return out;
}

namespace {

/// mmGeometry.h computeBBox (fmin / fmax from +-FLT_MAX), over several models.
void grow_box(const RenderModel& m, F3& lo, F3& hi) {
  for (const Float3& p : m.positions) {
    lo = {std::fmin(p[0], lo.x), std::fmin(p[1], lo.y), std::fmin(p[2], lo.z)};
    hi = {std::fmax(p[0], hi.x), std::fmax(p[1], hi.y), std::fmax(p[2], hi.z)};
  }
}
double box_diagonal(const RenderModel& m) {
  F3 lo{FLT_MAX, FLT_MAX, FLT_MAX}, hi{-FLT_MAX, -FLT_MAX, -FLT_MAX};
  grow_box(m, lo, hi);
  return detail::length(hi - lo);
}

}  // namespace

Frame frame_of(const RenderModel& a, const RenderModel& b) {
  F3 lo_a{FLT_MAX, FLT_MAX, FLT_MAX}, hi_a{-FLT_MAX, -FLT_MAX, -FLT_MAX};
  F3 lo_b = lo_a, hi_b = hi_a;
  grow_box(a, lo_a, hi_a);
  grow_box(b, lo_b, hi_b);
  // glm::min / glm::max of the two boxes, then RendererSw::render's sphere.
  const F3 lo{std::min(lo_a.x, lo_b.x), std::min(lo_a.y, lo_b.y), std::min(lo_a.z, lo_b.z)};
  const F3 hi{std::max(hi_a.x, hi_b.x), std::max(hi_a.y, hi_b.y), std::max(hi_a.z, hi_b.z)};
  const F3 half = (hi - lo) * 0.5f;
  Frame f;
  f.center = arr(lo + half);
  float radius = detail::length(half);
  radius = radius + radius / 100.0f;  // mmetric: 1 % so that the object stays off the borders
  f.radius = radius;
  return f;
}

double box_ratio(const RenderModel& a, const RenderModel& b) {
  return 100.0 * box_diagonal(b) / box_diagonal(a);
}

std::vector<Float3> fibonacci_directions(int count, const Float3& rotation_deg) {
  if (count < 2) throw std::invalid_argument("views: at least 2 (got " + std::to_string(count) + ")");
  const bool rotate = rotation_deg[2] != 0.0f;
  M4 rot = detail::identity();
  if (rotate) {
    constexpr float kRadPerDeg = static_cast<float>(0.01745329251994329576923690768489);  // glm::radians
    const float inclination = rotation_deg[0] * kRadPerDeg;
    const float azimuth = rotation_deg[1] * kRadPerDeg;
    const float intrinsic = rotation_deg[2] * kRadPerDeg;
    const float r = std::abs(std::sin(inclination));
    const F3 axis{std::cos(azimuth) * r, std::cos(inclination), std::sin(azimuth) * r};
    rot = detail::rotation(intrinsic, axis);
  }
  const double pi = std::atan(1.0) * 4;
  const float golden_rad = static_cast<float>(pi * (3. - std::sqrt(5.)));
  std::vector<Float3> out;
  for (int i = 0; i < count; ++i) {
    const float fi = static_cast<float>(i);
    const float y = 1 - (fi / static_cast<float>(count - 1)) * 2;
    const float radius = std::sqrt(1 - y * y);
    const float theta = golden_rad * fi;
    F3 pos{std::cos(theta) * radius, y, std::sin(theta) * radius};
    if (rotate) {
      const F4 r = detail::mul(rot, F4{pos.x, pos.y, pos.z, 1.0f});
      pos = {r.x, r.y, r.z};
    }
    out.push_back(arr(pos));
  }
  return out;
}

std::size_t View::drawn_pixels() const {
  std::size_t n = 0;
  for (std::size_t i = 3; i < rgba.size(); i += 4) n += rgba[i] != 0;
  return n;
}

namespace {

/// The transforms of one view (RendererSw::render).
struct Camera {
  M4 mvp;
  M4 viewport;
  F3 towards_camera;  ///< unit direction from the frame's centre to the camera
  float depth_range = 0;
  float pixels_per_unit = 0;
};

/// mmCompare.cpp: the up vector is +z for a view along +-y, +y otherwise.
F3 up_for(F3 dir) {
  const F3 d = F3{0, 1, 0} - F3{std::abs(dir.x), std::abs(dir.y), std::abs(dir.z)};
  return detail::length(d) < 1e-6 ? F3{0, 0, 1} : F3{0, 1, 0};
}

Camera camera_for(const Frame& frame, F3 direction, int width, int height) {
  const F3 dir = detail::normalize(direction);
  const F3 up = detail::normalize(up_for(direction));
  const float ratio = static_cast<float>(width) / static_cast<float>(height);
  const F3 center = f3(frame.center);
  const float radius = frame.radius;
  const F3 eye = center + dir * radius;
  const M4 view = detail::look_at(eye, center, up);
  const M4 glob = detail::mul(detail::translation({ratio * radius, radius, 0}),
                              detail::scaling({1.0f, 1.0f, -1.0f}));
  const M4 proj = detail::ortho(-ratio * radius, ratio * radius, -radius, radius, 0.0f,
                                2.0f * radius);
  const M4 model_view = detail::mul(view, detail::identity());
  Camera c;
  c.mvp = detail::mul(detail::mul(proj, glob), model_view);
  c.towards_camera = dir;
  const F3 far_point = eye - dir * radius * 2.0f;
  c.depth_range = std::abs(detail::mul(c.mvp, F4{far_point.x, far_point.y, far_point.z, 1.0f}).z);
  // viewport(0, 0, w, h) as mmetric builds it: its columns (w/2, 0, w/2, 0), (0, h/2, h/2, 0).
  c.viewport.c[0] = {static_cast<float>(width / 2.), 0, static_cast<float>(width / 2.), 0};
  c.viewport.c[1] = {0, static_cast<float>(height / 2.), static_cast<float>(height / 2.), 0};
  c.viewport.c[2] = {0, 0, 1, 0};
  c.viewport.c[3] = {0, 0, 0, 1};
  c.pixels_per_unit = static_cast<float>(width) / (2.0f * ratio * radius);
  return c;
}

/// Where a view is drawn: the rows [row0, row0 + rows) of a width x height image (a band, or
/// the whole image); pixel (x, y) at index x + (y - row0) * width of rgba (4 bytes) and depth.
struct Target {
  int width, height, row0, rows;
  std::uint8_t* rgba;
  float* depth;
  /// Per row of the target, the first and last column drawn (width, -1 when none).
  int* span_lo;
  int* span_hi;
  int last_row() const { return row0 + rows - 1; }
  std::size_t index(int x, int y) const {
    return static_cast<std::size_t>(x) +
           static_cast<std::size_t>(y - row0) * static_cast<std::size_t>(width);
  }
};

/// std::roundf (half away from zero) then int, inline: the shaders' colours are finite and far
/// below 2^31, where a - trunc(a) is exact.
int round_colour(float c) {
  const float a = std::fabs(c);
  const int t = static_cast<int>(a);
  const int r = a - static_cast<float>(t) >= 0.5f ? t + 1 : t;
  return c < 0 ? -r : r;
}

void write_pixel(const Target& t, int x, int y, float depth, const float colour[3]) {
  const std::size_t i = t.index(x, y);
  int& lo = t.span_lo[y - t.row0];
  int& hi = t.span_hi[y - t.row0];
  lo = std::min(lo, x);
  hi = std::max(hi, x);
  t.depth[i] = depth;
  for (int c = 0; c < 3; ++c) {
    t.rgba[i * 4 + c] = static_cast<std::uint8_t>(round_colour(colour[c]));
  }
  t.rgba[i * 4 + 3] = 255;
}

/// GLM's mat3 * vec3 on three corner values: (v0 b0 + v1 b1) + v2 b2, per component.
F3 interpolate(const F3 v[3], float b0, float b1, float b2) {
  return {v[0].x * b0 + v[1].x * b1 + v[2].x * b2, v[0].y * b0 + v[1].y * b1 + v[2].y * b2,
          v[0].z * b0 + v[1].z * b1 + v[2].z * b2};
}

/// What colours a face's pixels: its corners' colours (ShaderCpv), a texture (ShaderMap) or red
/// (ShaderRed), optionally lit by the headlight.
struct FaceShader {
  const F3* colour = nullptr;                  ///< 3 corner colours, 0..255
  const mesh::TextureImage* texture = nullptr;
  F3 uv[3];                                    ///< (u, v, 0) per corner
  const F3* normal = nullptr;                  ///< 3 corner normals: the headlight is on
  F3 towards_camera;
  bool two_sided = false;

  void shade(float b0, float b1, float b2, float out[3]) const {
    F3 rgb{255, 0, 0};
    if (texture) {
      const F3 uv_at = interpolate(uv, b0, b1, b2);
      const Float3 t = mesh::mm_texture_lookup(*texture, uv_at.x, uv_at.y, true);
      rgb = {t[0], t[1], t[2]};
    } else if (colour) {
      rgb = interpolate(colour, b0, b1, b2);
    }
    if (normal) {
      // mmetric's ShaderMapLight: Iamb + Idiff, clamped to 0..255.
      const F3 n = detail::normalize(interpolate(normal, b0, b1, b2));
      float lambert = detail::dot(n, towards_camera);
      lambert = two_sided ? std::abs(lambert) : std::max(lambert, 0.0f);
      if (std::isnan(lambert)) lambert = 0;  // a zero normal
      const F3 ambient = rgb * kAmbient;
      const F3 diffuse = (rgb * kDiffuse) * lambert;
      rgb = ambient + diffuse;
      rgb = {std::clamp(rgb.x, 0.0f, 255.0f), std::clamp(rgb.y, 0.0f, 255.0f),
             std::clamp(rgb.z, 0.0f, 255.0f)};
    }
    out[0] = rgb.x, out[1] = rgb.y, out[2] = rgb.z;
  }
  static constexpr float kAmbient = 0.4f;  // mmetric's RendererSw _materialAmbient
  static constexpr float kDiffuse = 0.6f;  // _materialDiffuse (white light)
};

/// A face's pixel box as mmetric's rasterize loop bounds it: corners' screen positions,
/// clamped to the image; rows and columns [int(lo), int(hi)].
struct PixelBox {
  float lo[2], hi[2];
};
PixelBox pixel_box(const F4 pts[3], int width, int height) {
  PixelBox b{{std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity()},
             {-std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()}};
  const float clamp[2] = {static_cast<float>(width - 1), static_cast<float>(height - 1)};
  for (int i = 0; i < 3; ++i) {
    const float p[2] = {pts[i].x / pts[i].w, pts[i].y / pts[i].w};
    for (int j = 0; j < 2; ++j) {
      b.lo[j] = std::max(0.0f, std::min(b.lo[j], p[j]));
      b.hi[j] = std::min(clamp[j], std::max(b.hi[j], p[j]));
    }
  }
  return b;
}

/// Four floats per instruction (SSE on every x86-64; a compiler splits them elsewhere): each
/// lane is IEEE single-precision arithmetic on its own pixel, the scalar expression's value.
using Floats = float __attribute__((vector_size(16)));
constexpr int kLanes = 4;

/// One face, as mmetric's rasterize loop body (pixels in rows instead of columns: a face
/// writes each pixel at most once, so the order within a face does not matter), on the
/// target's rows only (a pixel's values do not depend on which others are drawn), four pixels
/// of a row computed at once.
void draw_face(const Target& t, const F4 clip[3], const F4 pts[3], const FaceShader& shader) {
  const PixelBox box = pixel_box(pts, t.width, t.height);
  // u = cross((p2x - p0x, p1x - p0x, p0x - x), (p2y - p0y, p1y - p0y, p0y - y)).
  const float ax = pts[2].x - pts[0].x, ay = pts[1].x - pts[0].x;
  const float bx = pts[2].y - pts[0].y, by = pts[1].y - pts[0].y;
  const float uz = ax * by - bx * ay;
  const float z0 = clip[0].z, z1 = clip[1].z, z2 = clip[2].z;
  const float w0 = pts[0].w, w1 = pts[1].w, w2 = pts[2].w;
  const int y_end = std::min(static_cast<int>(box.hi[1]), t.last_row());
  const int x_lo = static_cast<int>(box.lo[0]), x_hi = static_cast<int>(box.hi[0]);
  for (int y = std::max(static_cast<int>(box.lo[1]), t.row0); y <= y_end; ++y) {
    const float bz = pts[0].y - static_cast<float>(y);
    for (int x = x_lo; x <= x_hi; x += kLanes) {
      const Floats xs = {static_cast<float>(x), static_cast<float>(x + 1),
                         static_cast<float>(x + 2), static_cast<float>(x + 3)};
      const Floats az = pts[0].x - xs;
      const Floats ux = ay * bz - by * az;
      const Floats uy = az * bx - bz * ax;
      const Floats s0 = 1.f - (ux + uy) / uz, s1 = uy / uz, s2 = ux / uz;
      const Floats c0 = s0 / w0, c1 = s1 / w1, c2 = s2 / w2;
      const Floats depth = z0 * c0 + z1 * c1 + z2 * c2;
      // Inside (barycentrics >= 0) with a depth (a NaN barycentric makes the depth NaN).
      const auto inside = (s0 >= 0) & (s1 >= 0) & (s2 >= 0) & (depth == depth);
      if (!(inside[0] | inside[1] | inside[2] | inside[3])) continue;
      for (int l = 0; l < kLanes && x + l <= x_hi; ++l) {
        if (!inside[l]) continue;
        const std::size_t i = t.index(x + l, y);
        if (depth[l] <= t.depth[i]) continue;
        float rgb[3];
        shader.shade(c0[l], c1[l], c2[l], rgb);
        write_pixel(t, x + l, y, depth[l], rgb);
      }
    }
  }
}

/// A point's splat on the screen: its projection, depth and the pixels of its footprint.
struct Splat {
  float px, py, depth;
  int x0, y0, x1, y1;
};

Splat splat_of(const Float3& p, const Camera& cam, int width, int height, float half_px) {
  const F4 clip = detail::mul(cam.mvp, F4{p[0], p[1], p[2], 1.0f});
  const F4 pt = detail::mul(cam.viewport, clip);
  Splat s;
  s.px = pt.x / pt.w;
  s.py = pt.y / pt.w;
  s.depth = clip.z;
  s.x0 = static_cast<int>(std::max(0.0f, std::ceil(s.px - half_px)));
  s.y0 = static_cast<int>(std::max(0.0f, std::ceil(s.py - half_px)));
  s.x1 = static_cast<int>(std::min(static_cast<float>(width - 1), std::floor(s.px + half_px)));
  s.y1 = static_cast<int>(std::min(static_cast<float>(height - 1), std::floor(s.py + half_px)));
  return s;
}

/// Calls f(x, y, squared screen distance to the centre) for each pixel of the footprint in
/// rows [row0, row_end].
template <class F>
void for_each_pixel(const Splat& s, int row0, int row_end, float half_px, bool disc, F&& f) {
  for (int y = std::max(s.y0, row0); y <= std::min(s.y1, row_end); ++y) {
    const float dy = static_cast<float>(y) - s.py;
    for (int x = s.x0; x <= s.x1; ++x) {
      const float dx = static_cast<float>(x) - s.px;
      const float d2 = dx * dx + dy * dy;
      if (disc && d2 > half_px * half_px) continue;
      f(x, y, d2);
    }
  }
}

/// Items (faces or splats) listed per band of rows, in their order (a pixel sees the items that
/// reach it in the order a whole-image pass would: the same ties).
struct Bins {
  std::vector<std::uint32_t> start, items;
  std::vector<std::array<int, 2>> ranges;
  /// rows(i) = {first, last} row of item i (first > last: none).
  template <class Rows>
  void fill(std::size_t count, int band_rows, int bands, Rows rows) {
    start.assign(static_cast<std::size_t>(bands) + 1, 0);
    ranges.resize(count);
    for (std::size_t i = 0; i < count; ++i) ranges[i] = rows(i);
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<std::uint32_t> next(start.begin(), start.end() - 1);
      for (std::size_t i = 0; i < count; ++i) {
        const std::array<int, 2> r = ranges[i];
        if (r[0] > r[1]) continue;
        for (int b = r[0] / band_rows; b <= r[1] / band_rows; ++b) {
          if (pass == 0) {
            ++start[static_cast<std::size_t>(b) + 1];
          } else {
            items[next[static_cast<std::size_t>(b)]++] = static_cast<std::uint32_t>(i);
          }
        }
      }
      if (pass == 0) {
        for (int b = 0; b < bands; ++b) start[b + 1] += start[b];
        items.resize(start.back());
      }
    }
  }
};

}  // namespace

namespace detail {

/// One model in one view (BandRaster's state): the camera, the vertices' clip coordinates
/// (meshes) or the splats and the front depths of pass 1 (clouds), the items per band.
struct BandRaster::State {
  const RenderModel* model = nullptr;
  RasterOptions options;
  Camera cam;
  int width = 0, height = 0, band_rows = 0, bands = 0;
  Bins bins;
  std::vector<F4> clip, screen;  // meshes: per vertex
  std::vector<Splat> splats;     // clouds
  std::vector<float> front, nearest;
  std::vector<int> span_lo, span_hi;  // the last band drawn
  int w2 = 0;
  float half_px = 0, epsilon = 0;

  void prepare_mesh();
  void draw_mesh(const Target& t) const;
  void prepare_splats();
  void draw_splats(const Target& t);
};

/// The faces not culled (clockwise faces culled: mmetric's default cwCulling), by rows.
void BandRaster::State::prepare_mesh() {
  const RenderModel& m = *model;
  clip.resize(m.positions.size());
  screen.resize(m.positions.size());
  for (std::size_t v = 0; v < clip.size(); ++v) {
    const Float3& p = m.positions[v];
    clip[v] = detail::mul(cam.mvp, F4{p[0], p[1], p[2], 1.0f});
    screen[v] = detail::mul(cam.viewport, clip[v]);
  }
  bins.fill(m.triangles.size(), band_rows, bands, [&](std::size_t f) -> std::array<int, 2> {
    const Triangle& tri = m.triangles[f];
    const F4 c[3] = {clip[tri[0]], clip[tri[1]], clip[tri[2]]};
    if (options.culling) {
      const F3 e1{c[1].x - c[0].x, c[1].y - c[0].y, c[1].z - c[0].z};
      const F3 e2{c[2].x - c[0].x, c[2].y - c[0].y, c[2].z - c[0].z};
      if (detail::cross(e1, e2).z <= 0) return {1, 0};
    }
    const F4 pts[3] = {screen[tri[0]], screen[tri[1]], screen[tri[2]]};
    const PixelBox box = pixel_box(pts, width, height);
    const int lo = std::max(static_cast<int>(box.lo[1]), 0);
    const int hi = std::min(static_cast<int>(box.hi[1]), height - 1);
    return {lo, hi};
  });
}

/// Faces fetched ahead while drawing.
constexpr std::size_t kAhead = 8;

void BandRaster::State::draw_mesh(const Target& t) const {
  const RenderModel& m = *model;
  const bool coloured = !m.colors_255.empty();
  const bool lit =
      options.lighting == Lighting::kHeadlight && m.normals.size() == m.positions.size();
  const std::size_t band = static_cast<std::size_t>(t.row0 / band_rows);
  const std::size_t end = bins.start[band + 1];
  for (std::size_t k = bins.start[band]; k < end; ++k) {
    // The faces of a band lie scattered in the canonical order: fetch ahead (no effect on values).
    if (k + 2 * kAhead < end) __builtin_prefetch(&m.triangles[bins.items[k + 2 * kAhead]]);
    if (k + kAhead < end) {
      for (std::uint32_t v : m.triangles[bins.items[k + kAhead]]) {
        __builtin_prefetch(&clip[v]);
        __builtin_prefetch(&screen[v]);
        if (coloured) __builtin_prefetch(&m.colors_255[v]);
      }
    }
    const std::uint32_t f = bins.items[k];
    const Triangle& tri = m.triangles[f];
    const F4 c[3] = {clip[tri[0]], clip[tri[1]], clip[tri[2]]};
    const F4 pts[3] = {screen[tri[0]], screen[tri[1]], screen[tri[2]]};
    FaceShader shader;
    F3 colour[3], normal[3];
    if (m.is_textured()) {
      shader.texture = &(*m.textures)[m.triangle_texture[f]];
      for (int i = 0; i < 3; ++i) shader.uv[i] = {m.uvs[tri[i]][0], m.uvs[tri[i]][1], 0};
    } else if (coloured) {
      for (int i = 0; i < 3; ++i) colour[i] = f3(m.colors_255[tri[i]]);
      shader.colour = colour;
    }
    if (lit) {
      for (int i = 0; i < 3; ++i) normal[i] = f3(m.normals[tri[i]]);
      shader.normal = normal;
      shader.towards_camera = cam.towards_camera;
      shader.two_sided = !options.culling;
    }
    draw_face(t, c, pts, shader);
  }
}

/// Splats in two passes (an epsilon-z-buffer, as surface splatting does: Pfister et al. 2000,
/// Botsch et al. 2005): pass 1 (here, over the whole view) finds the nearest depth that
/// footprints of twice the splat size reach (on a half-resolution buffer); pass 2 (draw_splats,
/// band by band) colours a pixel with the point whose centre is nearest to it among the points
/// within two splat sizes of that front depth (ties: the first in canonical order; two sizes
/// let a surface tilted up to about 60 degrees through). So the back of an object does not show
/// through the gaps between front splats (a gap stays empty), and colours are not blocks of
/// splat size.
void BandRaster::State::prepare_splats() {
  const RenderModel& m = *model;
  half_px = std::max(1.0f, m.splat_size * cam.pixels_per_unit) / 2;
  const bool disc = m.splat_shape == SplatShape::kDisc;
  // Two splat sizes in depth units (the frame's diameter spans depth_range).
  epsilon = 2 * m.splat_size * cam.depth_range * cam.pixels_per_unit / static_cast<float>(width);
  // Pass 1 with footprints twice as wide, on a depth buffer of half the resolution (each of its
  // cells a 2 x 2 block of pixels, a quarter of the work): a gap between the front's splats
  // (where no point landed) still gets the front's depth, so that the back does not fill it.
  w2 = (width + 1) / 2;
  const int h2 = (height + 1) / 2;
  front.assign(static_cast<std::size_t>(w2) * h2, -FLT_MAX);
  splats.resize(m.positions.size());
  for (std::size_t i = 0; i < splats.size(); ++i) {
    splats[i] = splat_of(m.positions[i], cam, width, height, half_px);
    // In the coarse buffer's units: a cell's centre at (X + 1/4, Y + 1/4), the splat's radius
    // 2 half_px / 2 = half_px, grown by a cell's half diagonal so that a cell is reached when
    // any of its pixels is.
    Splat wide = splats[i];
    const float radius = half_px;
    wide.px = wide.px / 2 - 0.25f;
    wide.py = wide.py / 2 - 0.25f;
    wide.x0 = static_cast<int>(std::max(0.0f, std::ceil(wide.px - radius)));
    wide.y0 = static_cast<int>(std::max(0.0f, std::ceil(wide.py - radius)));
    wide.x1 = static_cast<int>(std::min(static_cast<float>(w2 - 1), std::floor(wide.px + radius)));
    wide.y1 = static_cast<int>(std::min(static_cast<float>(h2 - 1), std::floor(wide.py + radius)));
    const float z = wide.depth;
    for_each_pixel(wide, 0, h2 - 1, radius, disc, [&](int x, int y, float) {
      float& f = front[static_cast<std::size_t>(x) + static_cast<std::size_t>(y) * w2];
      if (z > f) f = z;
    });
  }
  bins.fill(splats.size(), band_rows, bands, [&](std::size_t i) -> std::array<int, 2> {
    return {splats[i].y0, splats[i].y1};
  });
}

void BandRaster::State::draw_splats(const Target& t) {
  const RenderModel& m = *model;
  const bool disc = m.splat_shape == SplatShape::kDisc;
  const bool coloured = !m.colors_255.empty();
  nearest.assign(static_cast<std::size_t>(t.width) * t.rows,
                 std::numeric_limits<float>::infinity());
  const std::size_t band = static_cast<std::size_t>(t.row0 / band_rows);
  const std::size_t end = bins.start[band + 1];
  for (std::size_t k = bins.start[band]; k < end; ++k) {
    if (k + kAhead < end) {  // the points of a band lie scattered in the canonical order
      __builtin_prefetch(&splats[bins.items[k + kAhead]]);
      if (coloured) __builtin_prefetch(&m.colors_255[bins.items[k + kAhead]]);
    }
    const std::uint32_t i = bins.items[k];
    const Splat& s = splats[i];
    const float rgb[3] = {coloured ? m.colors_255[i][0] : 255.0f,
                          coloured ? m.colors_255[i][1] : 0.0f,
                          coloured ? m.colors_255[i][2] : 0.0f};
    for_each_pixel(s, t.row0, t.last_row(), half_px, disc, [&](int x, int y, float d2) {
      const std::size_t p = t.index(x, y);
      const std::size_t f = static_cast<std::size_t>(y / 2) * w2 + static_cast<std::size_t>(x / 2);
      if (s.depth < front[f] - epsilon || !(d2 < nearest[p])) return;
      nearest[p] = d2;
      write_pixel(t, x, y, s.depth, rgb);
    });
  }
}

}  // namespace detail

std::vector<Float3> cmdm18_directions() {
  const float d = static_cast<float>(1 / std::sqrt(2.0));
  return {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},  {0, -1, 0},  {0, 0, 1},  {0, 0, -1},
          {d, d, 0},  {d, -d, 0}, {-d, d, 0}, {-d, -d, 0}, {d, 0, d},  {d, 0, -d},
          {-d, 0, d}, {-d, 0, -d}, {0, d, d}, {0, d, -d},  {0, -d, d}, {0, -d, -d}};
}

namespace detail {

BandRaster::BandRaster() : state_(std::make_unique<State>()) {}
BandRaster::~BandRaster() = default;

void BandRaster::prepare(const RenderModel& model, const Frame& frame, const Float3& direction,
                         const RasterOptions& options, int band_rows) {
  if (options.resolution < 1) {
    throw std::invalid_argument("resolution: at least 1 pixel (got " +
                                std::to_string(options.resolution) + ")");
  }
  State& s = *state_;
  s.model = &model;
  s.options = options;
  s.width = s.height = options.resolution;
  s.band_rows = std::max(1, std::min(band_rows, s.height));
  s.bands = (s.height + s.band_rows - 1) / s.band_rows;
  s.cam = camera_for(frame, f3(direction), s.width, s.height);
  if (model.is_cloud()) {
    s.prepare_splats();
  } else {
    s.prepare_mesh();
  }
}

int BandRaster::width() const { return state_->width; }
int BandRaster::height() const { return state_->height; }
int BandRaster::bands() const { return state_->bands; }
int BandRaster::band_row0(int band) const { return band * state_->band_rows; }
int BandRaster::band_rows(int band) const {
  return std::min(state_->band_rows, state_->height - band_row0(band));
}
float BandRaster::depth_range() const { return state_->cam.depth_range; }
std::array<int, 2> BandRaster::drawn_columns(int row) const {
  return {state_->span_lo[static_cast<std::size_t>(row)],
          state_->span_hi[static_cast<std::size_t>(row)]};
}

void BandRaster::draw(int band, std::uint8_t* rgba, float* depth) {
  State& s = *state_;
  s.span_lo.assign(static_cast<std::size_t>(s.band_rows), s.width);
  s.span_hi.assign(static_cast<std::size_t>(s.band_rows), -1);
  const Target t{s.width, s.height, band_row0(band),  band_rows(band),
                 rgba,    depth,    s.span_lo.data(), s.span_hi.data()};
  const std::size_t n = static_cast<std::size_t>(t.width) * static_cast<std::size_t>(t.rows);
  std::fill(rgba, rgba + 4 * n, std::uint8_t{0});
  std::fill(depth, depth + n, -FLT_MAX);  // RendererSw's clear depth
  if (s.model->is_cloud()) {
    s.draw_splats(t);
  } else {
    s.draw_mesh(t);
  }
}

}  // namespace detail

View render_view(const RenderModel& model, const Frame& frame, const Float3& direction,
                 const RasterOptions& options) {
  detail::BandRaster raster;
  raster.prepare(model, frame, direction, options, options.resolution);
  View v;
  v.width = raster.width();
  v.height = raster.height();
  const std::size_t n = static_cast<std::size_t>(v.width) * static_cast<std::size_t>(v.height);
  reserve_with_huge_pages(v.rgba, n * 4);
  reserve_with_huge_pages(v.depth, n);
  v.rgba.resize(n * 4);
  v.depth.resize(n);
  v.depth_range = raster.depth_range();
  raster.draw(0, v.rgba.data(), v.depth.data());
  return v;
}

}  // namespace qm3d::render
