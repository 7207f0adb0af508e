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
#include <exception>
#include <limits>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include "qm3d/common/error.h"
#include "qm3d/common/result_io.h"

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

/// G: evalRayTriangle's ZERO_TOLERANCE on the determinant, which is (up to rounding) the
/// triangle's cross product along the ray's axis, i.e. twice its projected area in the file's
/// units: a face whose largest |cross component| is below it gets no ray hit (mmetric's
/// absolute threshold, which makes the samples depend on the unit).
constexpr float kRayEpsilon = 1e-06F;

/// G: evalRayTriangle (Moller-Trumbore, epsilon ZERO_TOLERANCE = 1e-6f): (t, u, v) on a hit.
bool ray_triangle(const Float3& origin, const Float3& dir, const Float3& v0, const Float3& v1,
                  const Float3& v2, Float3& res) {
  const Float3 edge1 = sub(v1, v0);
  const Float3 edge2 = sub(v2, v0);
  const Float3 pvec = cross(dir, edge2);
  const float det = dot(edge1, pvec);
  if (det > -kRayEpsilon && det < kRayEpsilon) return false;
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
  const std::vector<Rgb>* vertex = nullptr;  // [0, 1] at float precision
  const TexturedMesh* textured = nullptr;
  bool bilinear = false;
};

struct Grid {
  Float3 min;
  Float3 max;
  float step;
};

/// One face's corners as the sampler reads them (float32), and what decides its samples.
struct Corners {
  Float3 p[3];
  Float3 col[3] = {};       // vertex colours, 0..255
  float uv[3][2] = {};      // texture coordinates
  std::size_t texture = 0;  // the texture's index (textured meshes)
};

Corners corners_of(const ColoredMesh& mesh, std::size_t t, const Colouring& colouring) {
  const Triangle& tri = mesh.triangles[t];
  Corners c;
  for (int k = 0; k < 3; ++k) c.p[k] = to_float(mesh.positions[tri[k]]);
  if (colouring.textured != nullptr) {
    const TexturedMesh& tm = *colouring.textured;
    c.texture = tm.triangle_texture[t];
    for (int k = 0; k < 3; ++k) {
      const Uv& w = tm.uvs[tm.triangle_uvs[t][k]];
      c.uv[k][0] = static_cast<float>(w[0]);
      c.uv[k][1] = static_cast<float>(w[1]);
    }
  } else if (colouring.vertex != nullptr) {
    for (int k = 0; k < 3; ++k) {
      const Rgb& v = (*colouring.vertex)[tri[k]];
      c.col[k] = {mm_channel_255(v.r), mm_channel_255(v.g), mm_channel_255(v.b)};
    }
  }
  return c;
}

/// B: two faces with the same corners (positions, colours or UVs and texture, in the same
/// order) give bit-identical samples, all of which mmetric's ModelBuilder drops as duplicates:
/// the key under which a repeated face is sampled once.
struct CornersKey {
  std::array<std::uint32_t, 28> bits{};
  bool operator==(const CornersKey& o) const { return bits == o.bits; }
};

CornersKey key_of(const Corners& c) {
  CornersKey key;
  std::size_t n = 0;
  const auto put = [&](float f) {
    if (f == 0.0f) f = 0.0f;  // -0 and +0 sample alike
    std::memcpy(&key.bits[n++], &f, sizeof(float));
  };
  for (int k = 0; k < 3; ++k) {
    for (float f : c.p[k]) put(f);
    for (float f : c.col[k]) put(f);
    put(c.uv[k][0]);
    put(c.uv[k][1]);
  }
  key.bits[n] = static_cast<std::uint32_t>(c.texture);
  return key;
}

struct CornersKeyHash {
  std::size_t operator()(const CornersKey& k) const {
    std::size_t h = 1469598103934665603ull;
    for (std::uint32_t u : k.bits) h = (h ^ u) * 1099511628211ull;
    return h;
  }
};

/// What the sampler finds of one face before shooting rays.
enum class FaceKind {
  kSampled,     ///< sampled
  kDegenerate,  ///< area below DBL_EPSILON: skipped (as mmetric)
  kRepeat,      ///< the same corners as an earlier face: its samples are all duplicates
};

struct FacePlan {
  std::vector<FaceKind> kind;
  std::vector<std::size_t> first;  ///< per face: the face whose samples it repeats (or itself)
  std::size_t degenerate = 0, repeats = 0;
  std::size_t zero_normal = 0;    ///< |cross|^2 overflows float32: mmetric's normal is 0
  std::size_t below_epsilon = 0;  ///< no ray can hit it (kRayEpsilon)
  double estimated_samples = 0;   ///< sum of projected areas / step^2
};

/// The face's cross product (v2 - v1) x (v3 - v1) in float32 as mmetric computes it; throws
/// when it overflows (coordinates too large for mmetric's float32 arithmetic).
Float3 face_cross(const Corners& c, std::size_t t) {
  const Float3 x = cross(sub(c.p[1], c.p[0]), sub(c.p[2], c.p[0]));
  if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2])) {
    throw NumericError("grid sampling: face " + std::to_string(t) +
                       ": its cross product overflows float32 (mmetric's arithmetic; edges "
                       "longer than about 1e19): scale the mesh down");
  }
  return x;
}

/// Classifies every face (degenerate, repeat of an earlier one, sampled) and estimates the
/// sample count (sum over sampled faces of their area projected on the rays' axes / step^2).
FacePlan plan_faces(const ColoredMesh& mesh, const Colouring& colouring, const Grid& g,
                    bool all_axes) {
  const std::size_t n = mesh.triangles.size();
  FacePlan plan;
  plan.kind.resize(n, FaceKind::kSampled);
  plan.first.resize(n);
  std::unordered_map<CornersKey, std::size_t, CornersKeyHash> seen;
  const double cell = g.step > 0 ? double(g.step) * double(g.step) : 1.0;
  for (std::size_t t = 0; t < n; ++t) {
    const Corners c = corners_of(mesh, t, colouring);
    const auto [it, inserted] = seen.emplace(key_of(c), t);
    plan.first[t] = it->second;
    if (!inserted)
      plan.kind[t] = plan.kind[it->second] == FaceKind::kDegenerate ? FaceKind::kDegenerate
                                                                    : FaceKind::kRepeat;
    if (plan.kind[t] == FaceKind::kDegenerate) ++plan.degenerate;
    if (plan.kind[t] == FaceKind::kRepeat) ++plan.repeats;
    if (!inserted) continue;
    const Float3 x = face_cross(c, t);
    if (0.5 * static_cast<double>(std::sqrt(dot(x, x))) < DBL_EPSILON) {
      plan.kind[t] = FaceKind::kDegenerate;
      ++plan.degenerate;
      continue;
    }
    if (std::isinf(dot(x, x))) ++plan.zero_normal;
    const float largest = std::max({std::fabs(x[0]), std::fabs(x[1]), std::fabs(x[2])});
    if (largest < kRayEpsilon) ++plan.below_epsilon;
    const double projected =
        all_axes ? double(std::fabs(x[0])) + std::fabs(x[1]) + std::fabs(x[2]) : double(largest);
    plan.estimated_samples += 0.5 * projected / cell;
  }
  return plan;
}

/// The samples of one triangle, appended to `out`; false (nothing appended) when its rays
/// alone would take `out` past kMaxGridSamples. Throws when a hit overflows float32.
bool sample_triangle(const ColoredMesh& mesh, std::size_t t, const Colouring& colouring,
                     const Grid& g, bool all_axes, std::vector<Sample>& out) {
  const Corners corners = corners_of(mesh, t, colouring);
  const Float3& p1 = corners.p[0];
  const Float3& p2 = corners.p[1];
  const Float3& p3 = corners.p[2];
  const Float3 normal = normalize(cross(sub(p2, p1), sub(p3, p1)));
  Float3 tmin, tmax, lmin, lcnt;
  for (int k = 0; k < 3; ++k) {
    tmin[k] = std::min(std::min(std::min(FLT_MAX, p1[k]), p2[k]), p3[k]);
    tmax[k] = std::max(std::max(std::max(-FLT_MAX, p1[k]), p2[k]), p3[k]);
    lmin[k] = std::floor((tmin[k] - g.min[k]) / g.step);
    lcnt[k] = std::ceil((tmax[k] - g.min[k]) / g.step) - lmin[k];
  }
  const TextureImage* image =
      colouring.textured != nullptr ? &colouring.textured->textures[corners.texture] : nullptr;
  const int first_axis = all_axes ? 0 : main_axis(normal);
  const int last_axis = all_axes ? 2 : first_axis;
  double rays = 0;
  for (int axis = first_axis; axis <= last_axis; ++axis) {
    const int second = axis == 0 ? 1 : 0, third = axis == 2 ? 1 : 2;
    rays += (double(lcnt[second]) + 1) * (double(lcnt[third]) + 1);
  }
  if (rays + double(out.size()) > double(kMaxGridSamples)) return false;
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
        if (!std::isfinite(s.pos[0]) || !std::isfinite(s.pos[1]) || !std::isfinite(s.pos[2])) {
          throw NumericError("grid sampling: face " + std::to_string(t) +
                             ": a ray hit overflows float32 (mmetric's arithmetic; coordinates "
                             "beyond about 1e12): scale the mesh down");
        }
        s.nrm = normal;
        const float w0 = 1.0f - res[1] - res[2];
        if (image != nullptr) {
          const float u =
              corners.uv[0][0] * w0 + corners.uv[1][0] * res[1] + corners.uv[2][0] * res[2];
          const float v =
              corners.uv[0][1] * w0 + corners.uv[1][1] * res[1] + corners.uv[2][1] * res[2];
          s.col = mm_texture_lookup(*image, u, v, colouring.bilinear);
        } else {
          for (int k = 0; k < 3; ++k) {
            s.col[k] =
                corners.col[0][k] * w0 + corners.col[1][k] * res[1] + corners.col[2][k] * res[2];
          }
        }
        out.push_back(s);
      }
    }
  }
  return true;
}

Grid make_grid(const FloatBox& box, int grid_size) {
  Grid g{box.min, box.max, 0};
  float range = 0;
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(box.min[k]) || !std::isfinite(box.max[k]) || box.min[k] > box.max[k]) {
      throw NumericError(
          "grid sampling: the box is not a finite box (min above max or not "
          "finite)");
    }
  }
  const Float3 diag = sub(box.max, box.min);
  if (!std::isfinite(diag[0]) || !std::isfinite(diag[1]) || !std::isfinite(diag[2])) {
    throw NumericError(
        "grid sampling: the box's size overflows float32 (mmetric's arithmetic): "
        "scale the mesh down");
  }
  range = std::max(std::max(diag[0], diag[1]), diag[2]);
  g.step = range * (1.0F / static_cast<float>(grid_size - 1));
  int flat = 0;
  for (int k = 0; k < 3; ++k) flat += box.min[k] == box.max[k];
  if (flat >= 2) {
    throw NumericError(
        "grid sampling: the box is flat on two axes (a line or a point): no ray "
        "crosses it");
  }
  return g;
}

/// Bytes one sample takes at least while it is made and scored (the sample, its copy in the
/// output, the duplicate set's node and bucket, the scorer's double copy).
constexpr double kBytesPerSample = 160;

/// Refuses a sampling whose estimated sample count exceeds kMaxGridSamples or whose estimated
/// memory exceeds what the process may allocate, naming the estimate and a grid size that fits.
void check_estimate(const FacePlan& plan, int grid_size) {
  const double samples = plan.estimated_samples;
  const double memory = double(memory_limit_bytes());
  const double fits = std::min(double(kMaxGridSamples),
                               memory > 0 ? memory / kBytesPerSample : double(kMaxGridSamples));
  if (samples <= fits) return;
  const int suggested = std::max(2, static_cast<int>(grid_size * std::sqrt(fits / samples) * 0.9));
  std::string why = samples > double(kMaxGridSamples)
                        ? "more than the limit of " + std::to_string(kMaxGridSamples)
                        : "needing about " + short_number(samples * kBytesPerSample / 1e9) +
                              " GB, more than the " + short_number(memory / 1e9) +
                              " GB this process may use";
  throw MemoryLimitError("grid sampling: grid size " + std::to_string(grid_size) + " gives about " +
                         short_number(samples) +
                         " samples (the faces' area / "
                         "step^2), " +
                         why + "; a grid size of about " + std::to_string(suggested) + " fits");
}

void add_plan_warnings(const FacePlan& plan, std::size_t faces, GridSamples& out) {
  if (out.degenerate_faces > 0) {
    out.warnings.push_back(std::to_string(out.degenerate_faces) +
                           " faces of zero area were not sampled (as mmetric)");
  }
  if (plan.zero_normal > 0) {
    out.warnings.push_back(
        std::to_string(plan.zero_normal) + " of " + std::to_string(faces) +
        // As in mmetric: a zero normal, rays along x only, D2 0 on those faces (docs/formats.md).
        " faces: squared normal overflows float32 (edges > 1e9), zero as in mmetric; scale the "
        "meshes down");
  }
  if (plan.below_epsilon > 0) {
    out.warnings.push_back(
        std::to_string(plan.below_epsilon) + " of " + std::to_string(faces) +
        // Twice their projected area below 1e-6 in the file's units: unit-dependent, as mmetric.
        " faces below mmetric's absolute ray-triangle epsilon (1e-6) get no samples; scale the "
        "meshes up");
  }
}

/// The triangles sampled in parallel in fixed blocks (each distinct face once), gathered in
/// triangle order; an exception in a block (out of memory, float32 overflow) is rethrown after
/// the loop, the first block's first.
std::vector<std::vector<Sample>> sample_blocks(const ColoredMesh& mesh, const Colouring& colouring,
                                               const Grid& g, const FacePlan& plan,
                                               const GridSamplingOptions& o,
                                               std::vector<std::uint32_t>& face_samples) {
  const long n = static_cast<long>(mesh.triangles.size());
  constexpr long kBlock = 2048;
  const long blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::vector<Sample>> parts(static_cast<std::size_t>(blocks));
  std::vector<char> overflow(static_cast<std::size_t>(blocks), 0);
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(blocks));
  face_samples.assign(static_cast<std::size_t>(n), 0);
#pragma omp parallel for schedule(dynamic, 1) \
    num_threads(o.threads > 0 ? o.threads : omp_get_max_threads())
  for (long b = 0; b < blocks; ++b) {
    try {
      std::vector<Sample>& part = parts[b];
      for (long t = b * kBlock; t < std::min(n, (b + 1) * kBlock); ++t) {
        if (plan.kind[t] != FaceKind::kSampled) continue;
        const std::size_t before = part.size();
        if (!sample_triangle(mesh, static_cast<std::size_t>(t), colouring, g, o.all_axes, part)) {
          overflow[b] = 1;
          break;
        }
        face_samples[t] = static_cast<std::uint32_t>(
            std::min<std::size_t>(part.size() - before, std::numeric_limits<std::uint32_t>::max()));
      }
    } catch (...) {
      parts[b] = {};
      errors[b] = std::current_exception();
    }
  }
  for (long b = 0; b < blocks; ++b) {
    if (errors[b]) std::rethrow_exception(errors[b]);
  }
  std::size_t total = 0;
  for (long b = 0; b < blocks; ++b) {
    total += parts[b].size();
    if (overflow[b] || total > kMaxGridSamples) {
      throw MemoryLimitError("grid sampling: more than " + std::to_string(kMaxGridSamples) +
                             " samples (grid size " + std::to_string(o.grid_size) +
                             " is too fine for this mesh and box)");
    }
  }
  return parts;
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
      out.warnings.push_back(
          "the mesh's vertices reach outside the grid's box (as mmetric, the "
          "grid is extended past it: its nodes keep the box's origin and step)");
      break;
    }
  }
  const Grid g = make_grid(out.box, o.grid_size);
  out.step = g.step;
  const bool colours = colouring.vertex != nullptr || colouring.textured != nullptr;

  const FacePlan plan = plan_faces(mesh, colouring, g, o.all_axes);
  check_estimate(plan, o.grid_size);
  std::vector<std::uint32_t> face_samples;
  const std::vector<std::vector<Sample>> parts =
      sample_blocks(mesh, colouring, g, plan, o, face_samples);
  std::size_t total = 0;
  for (const std::vector<Sample>& part : parts) total += part.size();
  out.degenerate_faces = plan.degenerate;
  out.repeated_faces = plan.repeats;
  // B: a repeated face's samples, equal to its first occurrence's, all count as dropped.
  for (std::size_t t = 0; t < plan.kind.size(); ++t) {
    if (plan.kind[t] == FaceKind::kRepeat) out.duplicate_samples += face_samples[plan.first[t]];
  }

  if (total == 0) {
    throw NumericError("grid sampling: no samples (grid size " + std::to_string(o.grid_size) +
                       " is too coarse for its faces, or every face has zero area" +
                       (plan.below_epsilon > 0
                            ? ", or its faces are below mmetric's absolute ray-triangle epsilon "
                              "(twice their projected area under 1e-6 in the file's units: scale "
                              "the mesh up, e.g. to millimetres)"
                            : std::string()) +
                       ")");
  }
  add_plan_warnings(plan, mesh.triangles.size(), out);

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
