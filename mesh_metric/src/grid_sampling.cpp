// mmetric's grid sampling, rule by rule (the header lists them; M: mpeg-pcc-mmetric 1.1.7 @
// 5faa660, source/lib/source/mmSample.cpp Sample::meshToPcGrid; G: mmGeometry.{h,cpp}; I:
// mmImage.h; B: mmModel.h ModelBuilder). Every operation is float32 in glm's order (glm's
// cross, dot = (x + y) + z, normalize = v * (1 / sqrt(dot(v, v)))); this file is compiled
// with -ffp-contract=off so that no multiply-add is fused, as in mmetric's x86-64 build.
#include "qm3d/mesh/grid_sampling.h"

#include <omp.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <unordered_set>

#include "qm3d/common/error.h"

namespace qm3d::mesh {
namespace {

Float3 sub(const Float3& a, const Float3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

Float3 cross(const Float3& x, const Float3& y) {
  return {x[1] * y[2] - y[1] * x[2], x[2] * y[0] - y[2] * x[0], x[0] * y[1] - y[0] * x[1]};
}

float dot(const Float3& a, const Float3& b) {
  const float t0 = a[0] * b[0], t1 = a[1] * b[1], t2 = a[2] * b[2];
  return t0 + t1 + t2;
}

Float3 normalize(const Float3& v) {
  const float inv = 1.0f / std::sqrt(dot(v, v));
  return {v[0] * inv, v[1] * inv, v[2] * inv};
}

Float3 to_float(const Vec3& v) {
  return {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
}

/// G: evalRayTriangle (Moller-Trumbore, epsilon ZERO_TOLERANCE = 1e-6f): (t, u, v) on a hit.
bool ray_triangle(const Float3& origin, const Float3& dir, const Float3& v0, const Float3& v1,
                  const Float3& v2, Float3& res) {
  constexpr float kEpsilon = 1e-06F;
  const Float3 edge1 = sub(v1, v0);
  const Float3 edge2 = sub(v2, v0);
  const Float3 pvec = cross(dir, edge2);
  const float det = dot(edge1, pvec);
  if (det > -kEpsilon && det < kEpsilon) return false;
  const float inv_det = 1.0f / det;
  const Float3 tvec = sub(origin, v0);
  const float u = dot(tvec, pvec) * inv_det;
  if (u < 0.0f || u > 1.0f) return false;
  const Float3 qvec = cross(tvec, edge1);
  const float v = dot(dir, qvec) * inv_det;
  if (v < 0.0f || u + v > 1.0f) return false;
  res = {dot(edge2, qvec) * inv_det, u, v};
  return true;
}

/// M: the axis order by the normal's components (--useNormal); the first one is used.
int main_axis(const Float3& n) {
  const float a = std::fabs(n[0]), b = std::fabs(n[1]), c = std::fabs(n[2]);
  if (a >= b && a >= c) return 0;
  if (b >= a && b >= c) return 1;
  return 2;
}

/// A sample before duplicates are dropped: colours still float (0..255).
struct Sample {
  Float3 pos, col, nrm;
};

/// B: CompareVertex's equality (==, so -0 equals +0) and a hash consistent with it.
bool same(const Sample& a, const Sample& b) {
  return a.pos == b.pos && a.col == b.col && a.nrm == b.nrm;
}

std::size_t hash_of(const Sample& s) {
  std::size_t h = 1469598103934665603ull;
  for (const Float3* v : {&s.pos, &s.col, &s.nrm}) {
    for (float f : *v) {
      if (f == 0.0f) f = 0.0f;  // -0 and +0: one key
      std::uint32_t u = 0;
      std::memcpy(&u, &f, sizeof u);
      h = (h ^ u) * 1099511628211ull;
    }
  }
  return h;
}

/// How a triangle's corners are coloured: vertex colours, a texture, or none.
struct Colouring {
  const std::vector<Rgb>* vertex = nullptr;          // [0, 1] at float precision
  const TexturedMesh* textured = nullptr;
  bool bilinear = false;
};

struct Grid {
  Float3 min;
  Float3 max;
  float step;
};

enum class TriangleStatus { kSampled, kDegenerate, kTooMany };

/// The samples of one triangle, appended to `out`; kTooMany (nothing appended) when its rays
/// alone would take `out` past kMaxGridSamples.
TriangleStatus sample_triangle(const ColoredMesh& mesh, std::size_t t, const Colouring& colouring,
                     const Grid& g, bool all_axes, std::vector<Sample>& out) {
  const Triangle& tri = mesh.triangles[t];
  const Float3 p1 = to_float(mesh.positions[tri[0]]);
  const Float3 p2 = to_float(mesh.positions[tri[1]]);
  const Float3 p3 = to_float(mesh.positions[tri[2]]);
  const Float3 c = cross(sub(p2, p1), sub(p3, p1));
  if (0.5 * static_cast<double>(std::sqrt(dot(c, c))) < DBL_EPSILON) {
    return TriangleStatus::kDegenerate;
  }
  const Float3 normal = normalize(c);
  Float3 tmin, tmax, lmin, lcnt;
  for (int k = 0; k < 3; ++k) {
    tmin[k] = std::min(std::min(std::min(FLT_MAX, p1[k]), p2[k]), p3[k]);
    tmax[k] = std::max(std::max(std::max(-FLT_MAX, p1[k]), p2[k]), p3[k]);
    lmin[k] = std::floor((tmin[k] - g.min[k]) / g.step);
    lcnt[k] = std::ceil((tmax[k] - g.min[k]) / g.step) - lmin[k];
  }
  // Corner colours (0..255 floats) and UVs.
  Float3 col[3] = {};
  float uv[3][2] = {};
  const TextureImage* image = nullptr;
  if (colouring.textured != nullptr) {
    const TexturedMesh& tm = *colouring.textured;
    image = &tm.textures[tm.triangle_texture[t]];
    for (int k = 0; k < 3; ++k) {
      const Uv& w = tm.uvs[tm.triangle_uvs[t][k]];
      uv[k][0] = static_cast<float>(w[0]);
      uv[k][1] = static_cast<float>(w[1]);
    }
  } else if (colouring.vertex != nullptr) {
    for (int k = 0; k < 3; ++k) {
      const Rgb& v = (*colouring.vertex)[tri[k]];
      col[k] = {mm_channel_255(v.r), mm_channel_255(v.g), mm_channel_255(v.b)};
    }
  }
  const int first_axis = all_axes ? 0 : main_axis(normal);
  const int last_axis = all_axes ? 2 : first_axis;
  double rays = 0;
  for (int axis = first_axis; axis <= last_axis; ++axis) {
    const int second = axis == 0 ? 1 : 0, third = axis == 2 ? 1 : 2;
    rays += (double(lcnt[second]) + 1) * (double(lcnt[third]) + 1);
  }
  if (rays + double(out.size()) > double(kMaxGridSamples)) return TriangleStatus::kTooMany;
  for (int axis = first_axis; axis <= last_axis; ++axis) {
    const int second = axis == 0 ? 1 : 0;
    const int third = axis == 2 ? 1 : 2;
    if (g.min[second] == g.max[second] || g.min[third] == g.max[third]) continue;
    Float3 origin{0, 0, 0}, dir{0, 0, 0};
    origin[axis] = g.step == 0.0f ? g.min[axis] - 0.5f : g.min[axis] + lmin[axis] * g.step;
    dir[axis] = 1.0f;
    for (std::size_t i = 0; static_cast<float>(i) <= lcnt[second]; ++i) {
      for (std::size_t j = 0; static_cast<float>(j) <= lcnt[third]; ++j) {
        origin[second] = g.min[second] + (lmin[second] + static_cast<float>(i)) * g.step;
        origin[third] = g.min[third] + (lmin[third] + static_cast<float>(j)) * g.step;
        Float3 res;
        if (!ray_triangle(origin, dir, p1, p2, p3, res)) continue;
        Sample s;
        for (int k = 0; k < 3; ++k) s.pos[k] = origin[k] + dir[k] * res[0];
        s.nrm = normal;
        const float w0 = 1.0f - res[1] - res[2];
        if (image != nullptr) {
          const float u = uv[0][0] * w0 + uv[1][0] * res[1] + uv[2][0] * res[2];
          const float v = uv[0][1] * w0 + uv[1][1] * res[1] + uv[2][1] * res[2];
          s.col = mm_texture_lookup(*image, u, v, colouring.bilinear);
        } else {
          for (int k = 0; k < 3; ++k) {
            s.col[k] = col[0][k] * w0 + col[1][k] * res[1] + col[2][k] * res[2];
          }
        }
        out.push_back(s);
      }
    }
  }
  return TriangleStatus::kSampled;
}

Grid make_grid(const FloatBox& box, int grid_size) {
  Grid g{box.min, box.max, 0};
  float range = 0;
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(box.min[k]) || !std::isfinite(box.max[k]) || box.min[k] > box.max[k]) {
      throw NumericError("grid sampling: the box is not a finite box (min above max or not "
                         "finite)");
    }
  }
  const Float3 diag = sub(box.max, box.min);
  range = std::max(std::max(diag[0], diag[1]), diag[2]);
  g.step = range * (1.0F / static_cast<float>(grid_size - 1));
  int flat = 0;
  for (int k = 0; k < 3; ++k) flat += box.min[k] == box.max[k];
  if (flat >= 2) {
    throw NumericError("grid sampling: the box is flat on two axes (a line or a point): no ray "
                       "crosses it");
  }
  return g;
}

GridSamples sample(const ColoredMesh& mesh, const Colouring& colouring,
                   const GridSamplingOptions& o) {
  constexpr int kMaxGridSize = 1000000;
  if (o.grid_size < 2 || o.grid_size > kMaxGridSize) {
    throw std::invalid_argument("grid size: must be in [2, 1000000], got " +
                                std::to_string(o.grid_size));
  }
  GridSamples out;
  const FloatBox own = vertex_box(mesh.positions);
  out.box = o.box ? *o.box : own;
  for (int k = 0; o.box && k < 3; ++k) {
    if (own.min[k] < out.box.min[k] || own.max[k] > out.box.max[k]) {
      out.warnings.push_back("the mesh's vertices reach outside the grid's box (as mmetric, the "
                             "grid is extended past it: its nodes keep the box's origin and step)");
      break;
    }
  }
  const Grid g = make_grid(out.box, o.grid_size);
  out.step = g.step;
  const bool colours = colouring.vertex != nullptr || colouring.textured != nullptr;

  // Triangles sampled in parallel in fixed blocks, gathered in triangle order.
  const long n = static_cast<long>(mesh.triangles.size());
  constexpr long kBlock = 2048;
  const long blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::vector<Sample>> parts(static_cast<std::size_t>(blocks));
  std::vector<std::size_t> degenerate(static_cast<std::size_t>(blocks), 0);
  std::vector<char> overflow(static_cast<std::size_t>(blocks), 0);
#pragma omp parallel for schedule(dynamic, 1) num_threads(o.threads > 0 ? o.threads : omp_get_max_threads())
  for (long b = 0; b < blocks; ++b) {
    std::vector<Sample>& part = parts[b];
    for (long t = b * kBlock; t < std::min(n, (b + 1) * kBlock); ++t) {
      const TriangleStatus status =
          sample_triangle(mesh, static_cast<std::size_t>(t), colouring, g, o.all_axes, part);
      if (status == TriangleStatus::kDegenerate) ++degenerate[b];
      if (status == TriangleStatus::kTooMany) {
        overflow[b] = 1;
        break;
      }
    }
  }
  std::size_t total = 0;
  for (long b = 0; b < blocks; ++b) {
    total += parts[b].size();
    out.degenerate_faces += degenerate[b];
    if (overflow[b] || total > kMaxGridSamples) {
      throw NumericError("grid sampling: more than " + std::to_string(kMaxGridSamples) +
                         " samples (grid size " + std::to_string(o.grid_size) +
                         " is too fine for this mesh and box)");
    }
  }

  if (total == 0) {
    throw NumericError("grid sampling: no samples (grid size " + std::to_string(o.grid_size) +
                       " is too coarse for its faces, or every face has zero area)");
  }
  if (out.degenerate_faces > 0) {
    out.warnings.push_back(std::to_string(out.degenerate_faces) +
                           " faces of zero area were not sampled (as mmetric)");
  }

  // B: pushVertex drops a sample equal to one already kept.
  const auto hash = [](const Sample* s) { return hash_of(*s); };
  const auto eq = [](const Sample* a, const Sample* b) { return same(*a, *b); };
  std::unordered_set<const Sample*, decltype(hash), decltype(eq)> seen(total, hash, eq);
  out.positions.reserve(total);
  out.normals.reserve(total);
  if (colours) out.colours.reserve(total);
  for (const std::vector<Sample>& part : parts) {
    for (const Sample& s : part) {
      if (!seen.insert(&s).second) {
        ++out.duplicate_samples;
        continue;
      }
      out.positions.push_back(s.pos);
      out.normals.push_back(s.nrm);
      if (!colours) continue;
      std::array<std::uint8_t, 3> c8;
      for (int k = 0; k < 3; ++k) {
        // mmetric writes (unsigned short) roundf(c) and reads it back as uchar.
        c8[k] = static_cast<std::uint8_t>(std::min(std::max(std::round(s.col[k]), 0.0f), 255.0f));
      }
      out.colours.push_back(c8);
    }
  }
  return out;
}

}  // namespace

GridSamples sample_grid(const ColoredMesh& mesh, const GridSamplingOptions& options) {
  Colouring c;
  if (!mesh.colors.empty()) c.vertex = &mesh.colors;
  return sample(mesh, c, options);
}

GridSamples sample_grid(const TexturedMesh& mesh, const GridSamplingOptions& options) {
  Colouring c;
  c.textured = &mesh;
  c.bilinear = options.bilinear;
  return sample(mesh.file.mesh, c, options);
}

}  // namespace qm3d::mesh
