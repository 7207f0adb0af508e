#include "qm3d/mesh/sampling.h"

#include <algorithm>
#include <cmath>
#include <locale>
#include <random>
#include <sstream>
#include <string>

#include "qm3d/common/error.h"
#include "qm3d/common/result_io.h"
#include "vec3_ops.h"

namespace qm3d::mesh {
namespace {

using detail::cross;
using detail::dot;
using detail::sub;

// 53 random bits -> a double uniform in [0, 1), identical on every standard library (unlike
// std::uniform_real_distribution, whose algorithm is unspecified).
constexpr int kMantissaShift = 11;
constexpr double kTwoToMinus53 = 0x1.0p-53;

double uniform01(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> kMantissaShift) * kTwoToMinus53;
}

// Where a sample lies: its triangle and the barycentric weights of the triangle's corners 1, 2.
struct SurfacePoint {
  std::uint32_t triangle = 0;
  double w1 = 0;
  double w2 = 0;
};

double triangle_area(const ColoredMesh& mesh, const Triangle& t) {
  const Vec3& a = mesh.positions[t[0]];
  const Vec3 n = cross(sub(mesh.positions[t[1]], a), sub(mesh.positions[t[2]], a));
  return 0.5 * std::sqrt(dot(n, n));
}

// Running sums of the triangle areas, summed in triangle order (deterministic).
std::vector<double> cumulative_areas(const ColoredMesh& mesh) {
  std::vector<double> cumulative(mesh.triangles.size());
  double sum = 0;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    sum += triangle_area(mesh, mesh.triangles[i]);
    cumulative[i] = sum;
  }
  if (cumulative.empty() || !(sum > 0) || !std::isfinite(sum)) {
    throw NumericError("surface sampling: the mesh has no area");
  }
  return cumulative;
}

// Draws the samples serially from one stream: triangle by area, point by the sqrt trick.
std::vector<SurfacePoint> draw_points(const std::vector<double>& cumulative, std::size_t count,
                                      std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const double total = cumulative.back();
  std::vector<SurfacePoint> points(count);
  for (auto& p : points) {
    const double target = uniform01(rng) * total;
    const auto it = std::upper_bound(cumulative.begin(), cumulative.end(), target);
    const auto index = std::min<std::size_t>(it - cumulative.begin(), cumulative.size() - 1);
    const double r1 = std::sqrt(uniform01(rng));
    const double r2 = uniform01(rng);
    p = {static_cast<std::uint32_t>(index), r1 * (1 - r2), r1 * r2};
  }
  return points;
}

// a + w1 (b - a) + w2 (c - a): exact when a, b and c are equal.
double interpolate(double a, double b, double c, const SurfacePoint& p) {
  return a + p.w1 * (b - a) + p.w2 * (c - a);
}

Vec3 position_of(const ColoredMesh& mesh, const SurfacePoint& p) {
  const Triangle& t = mesh.triangles[p.triangle];
  const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
  return {interpolate(a[0], b[0], c[0], p), interpolate(a[1], b[1], c[1], p),
          interpolate(a[2], b[2], c[2], p)};
}

Rgb vertex_color_of(const ColoredMesh& mesh, const SurfacePoint& p) {
  const Triangle& t = mesh.triangles[p.triangle];
  const Rgb &a = mesh.colors[t[0]], &b = mesh.colors[t[1]], &c = mesh.colors[t[2]];
  return {interpolate(a.r, b.r, c.r, p), interpolate(a.g, b.g, c.g, p),
          interpolate(a.b, b.b, c.b, p)};
}

Rgb texture_color_of(const TexturedMesh& mesh, const SurfacePoint& p) {
  const Triangle& t = mesh.triangle_uvs[p.triangle];
  const Uv &a = mesh.uvs[t[0]], &b = mesh.uvs[t[1]], &c = mesh.uvs[t[2]];
  const Uv uv{interpolate(a[0], b[0], c[0], p), interpolate(a[1], b[1], c[1], p)};
  return sample_texture(mesh.textures[mesh.triangle_texture[p.triangle]], uv);
}

std::vector<SurfacePoint> draw_for(const ColoredMesh& mesh, const SamplingOptions& options) {
  const std::vector<double> cumulative = cumulative_areas(mesh);
  return draw_points(cumulative, sample_count(options, cumulative.back()), options.seed);
}

template <typename ColorOf>
ColoredCloud build_cloud(const ColoredMesh& mesh, const std::vector<SurfacePoint>& points,
                         const ColorOf& color_of) {
  ColoredCloud cloud;
  cloud.positions.reserve(points.size());
  cloud.colors.reserve(points.size());
  for (const SurfacePoint& p : points) {
    cloud.positions.push_back(position_of(mesh, p));
    cloud.colors.push_back(color_of(p));
  }
  return cloud;
}

}  // namespace

std::size_t sample_count(const SamplingOptions& options, double total_area) {
  const bool by_points = options.points > 0, by_density = options.density != 0;
  if (by_points == by_density) {
    throw NumericError("surface sampling: set exactly one of points and density");
  }
  if (by_points) {
    if (options.points > kMaxSamples) {
      throw NumericError("surface sampling: " + std::to_string(options.points) +
                         " points are more than the " + std::to_string(kMaxSamples) +
                         " one sampling draws");
    }
    return options.points;
  }
  if (!(options.density > 0) || !std::isfinite(options.density)) {
    throw NumericError("surface sampling: density " + short_number(options.density) +
                       " is not a positive number");
  }
  const double count = std::round(options.density * total_area);
  if (!(count >= 1)) {
    throw NumericError("surface sampling: density " + short_number(options.density) +
                       " gives no point on an area of " + short_number(total_area));
  }
  // Compared as doubles: a count past 2^64 must not wrap round when converted.
  if (!(count <= static_cast<double>(kMaxSamples))) {
    throw NumericError("surface sampling: density " + short_number(options.density) + " gives " +
                       short_number(count) + " points on an area of " + short_number(total_area) +
                       ", more than the " + std::to_string(kMaxSamples) +
                       " one sampling draws (lower the density)");
  }
  return static_cast<std::size_t>(count);
}

ColoredCloud sample_surface(const ColoredMesh& mesh, const SamplingOptions& options) {
  if (mesh.colors.size() != mesh.positions.size()) {
    throw NumericError("surface sampling: the mesh has no vertex colours");
  }
  const std::vector<SurfacePoint> points = draw_for(mesh, options);
  return build_cloud(mesh, points, [&](const SurfacePoint& p) { return vertex_color_of(mesh, p); });
}

ColoredCloud sample_surface(const TexturedMesh& mesh, const SamplingOptions& options) {
  const ColoredMesh& geometry = mesh.file.mesh;
  const std::vector<SurfacePoint> points = draw_for(geometry, options);
  return build_cloud(geometry, points,
                     [&](const SurfacePoint& p) { return texture_color_of(mesh, p); });
}

}  // namespace qm3d::mesh
