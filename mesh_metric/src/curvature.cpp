#include "curvature.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "vec3_ops.h"
#include "walk_scratch.h"

namespace qm3d::mesh::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// A tensor being accumulated; `valid` false once an edge carrying kVoidsTensor contributed.
struct Tensor {
  double t[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  bool valid = true;
};

void add_edge_tensor(double tensor[3][3], const Vec3& vec, double coeff) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) tensor[i][j] += vec[i] * vec[j] * coeff;
  }
}

// Half-edge k's contribution, `vec` (clipped where it crosses the sphere): beta vec vec^T / |vec|
// with beta its dihedral angle; kNoContribution (NaN) adds nothing; kVoidsTensor
// (DegenerateEdges::kVoidTensor) voids the tensor: MEPP2's is NaN there. Inline: it runs once per
// edge of every walk (called out of line, the curvature stage took 3 % more time).
//
// `reversed`: the clip scaled the edge by a negative t (see clipped_backwards); MEPP2 computes
// the angle's sine from the clipped vector, so its beta has the opposite sign there.
inline void add_edge(const HalfedgeMesh& m, std::uint32_t k, const Vec3& vec, Tensor& tensor,
                     bool reversed) {
  const double stored = m.rings.dihedral[k];
  if (stored == kVoidsTensor) {
    tensor.valid = false;
  } else if (!std::isnan(stored)) {
    const double beta = reversed ? -stored : stored;
    const double len = norm(vec);
    if (len > 0) add_edge_tensor(tensor.t, vec, beta / len);
  }
}

// True when sphere_clip_vector turned `edge` into `clipped` with a negative t. MEPP2's
// sphere_clip_vector has no `t < 0` test (it is commented out there), and its curvature walks
// take the dihedral angle's sine from the clipped vector (curvature_cmdm.hpp and Manifold/
// Curvature/curvature.hpp: sine = (n1 x n2) . vec / |vec|), so such an edge adds its tensor with
// beta negated. t < 0 needs the edge's start outside the sphere, which a walk reaches through an
// edge shorter than MEPP2's absolute epsilon (kClipEpsilon: "inside" whatever the radius): on
// meshes of box ~1e-7 (issue 37: blob3 at 1e-7, 0.0491963 without this rule, MEPP2 0.0492054).
// The short-edge warning (multiscale.cpp) names the cause and the remedy.
inline bool clipped_backwards(const Vec3& clipped, const Vec3& edge) {
  return dot(clipped, edge) < 0;
}

// sphere_clip_vector's test, inlined into the walks.
__attribute__((always_inline)) inline bool clip(const Vec3& o, double r, const Vec3& p, Vec3& v) {
  const Vec3 w = sub(p, o);
  const double a = dot(v, v);
  if (std::fabs(a) < kClipEpsilon) return false;
  if (far_end_clearly_inside(w, v, a, r)) return false;  // what t >= 1 below returns
  const double b = 2.0 * dot(v, w);
  const double c = dot(w, w) - r * r;
  const double delta = b * b - 4. * a * c;
  if (delta < 0.) return true;  // numerical noise: treated as crossing, unclipped
  const double t = (-b + std::sqrt(delta)) / (2.0 * a);
  if (t >= 1.) return false;  // the far end is inside the sphere
  v = scale(v, t);
  return true;
}

// The curvature tensor of vertex v0 within the ball of radius r (MEPP2's walk, one radius).
Tensor vertex_tensor(const HalfedgeMesh& m, std::uint32_t v0, double r, CurvatureVariant variant,
                     WalkScratch& scratch) {
  const Vec3& o = m.positions[v0];
  const bool strict = variant == CurvatureVariant::kGeneric;
  Tensor tensor;
  walk_outward(m, v0, strict, scratch,
               [&](std::uint32_t v, std::uint32_t k, std::uint32_t w, Vec3 vec) {
                 const Vec3 edge = vec;
                 const bool isect = clip(o, r, m.positions[v], vec);
                 if (variant == CurvatureVariant::kGeneric || isect) {
                   add_edge(m, k, vec, tensor, clipped_backwards(vec, edge));
                 }
                 if (!isect) scratch.enter(w);
               });
  const double area = kPi * r * r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) tensor.t[i][j] /= area;
  }
  return tensor;
}

// The tensors of vertex v0 at each of `radii` (increasing) in one walk (walk_outward_levels):
// tensors[j] is what vertex_tensor gives at radii[j] alone, summed in another order. An edge
// that crosses the sphere at level j contributes (clipped) at that level only; an edge inside at
// level j contributes its whole vector at every level from j on (kGeneric), gathered in
// `inside`.
void vertex_tensors(const HalfedgeMesh& m, std::uint32_t v0, const std::vector<double>& radii,
                    CurvatureVariant variant, MultiWalkScratch& scratch,
                    std::vector<Tensor>& tensors) {
  const Vec3& o = m.positions[v0];
  const bool generic = variant == CurvatureVariant::kGeneric;
  Tensor inside, crossing;
  walk_outward_levels(
      m, v0, generic, radii.size(), scratch,
      [&](std::size_t level, std::uint32_t v, std::uint32_t k, std::uint32_t w, Vec3 vec) {
        const Vec3 edge = vec;
        const bool isect = clip(o, radii[level], m.positions[v], vec);
        if (!isect) scratch.enter(w);
        if (generic || isect) {
          add_edge(m, k, vec, isect ? crossing : inside, clipped_backwards(vec, edge));
        }
        return isect;
      },
      [&](std::size_t level) {
        const double area = kPi * radii[level] * radii[level];
        Tensor& out = tensors[level];
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) out.t[i][j] = (inside.t[i][j] + crossing.t[i][j]) / area;
        }
        out.valid = inside.valid && crossing.valid;
        crossing = Tensor{};
      });
}

// maxdim * (|l0| + |l1|) / 2 with l0, l1 the eigenvalues of largest magnitude.
double post_process(const double tensor[3][3], double maxdim) {
  Eigen::Matrix3d t;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) t(i, j) = tensor[i][j];
  }
  Eigen::Vector3d values;
  if (t(0, 1) == 0 && t(0, 2) == 0 && t(1, 0) == 0 && t(1, 2) == 0 && t(2, 0) == 0 &&
      t(2, 1) == 0) {
    values = t.diagonal();
  } else {
    // Closed-form 3x3 eigenvalues (Eigen computeDirect): same values to ~1e-15 relative as
    // MEPP2's iterative EigenSolver on most tensors, several times faster. Some tensors differ
    // more: on blob5 quantised to 8 bits local MSDM2 values move by up to 3e-9 and CMDM's by up
    // to 3e-10 (with EigenSolver both agree with MEPP2's to 5e-15).
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(t, Eigen::EigenvaluesOnly);
    if (solver.info() != Eigen::Success) return 0.0;
    values = solver.eigenvalues();
  }
  double mags[3] = {std::fabs(values[0]), std::fabs(values[1]), std::fabs(values[2])};
  std::sort(mags, mags + 3, [](double a, double b) { return a > b; });
  return (mags[0] * maxdim + mags[1] * maxdim) / 2.0;
}

// A void tensor: MEPP2's eigen-solver fails on its NaN tensor and sets both principal
// curvatures to 0 (SPEC-CMDM §MSDM2-degenerate).
double curvature_of(const Tensor& t, double maxdim) {
  return t.valid ? post_process(t.t, maxdim) : 0.0;
}

}  // namespace

ShortEdges edges_under_clip_epsilon(const HalfedgeMesh& mesh) {
  ShortEdges count;
  for (std::uint32_t v = 0; v < mesh.positions.size(); ++v) {
    for (std::uint32_t k = mesh.rings.begin(v); k < mesh.rings.end(v); ++k) {
      const std::uint32_t w = mesh.rings.source[k];
      if (w <= v) continue;
      const Vec3 e = sub(mesh.positions[w], mesh.positions[v]);
      const double squared = dot(e, e);
      if (squared == 0.0) {
        ++count.zero;
      } else if (std::fabs(squared) < kClipEpsilon) {
        ++count.tiny;
      }
    }
  }
  return count;
}

bool sphere_clip_vector(const Vec3& o, double r, const Vec3& p, Vec3& v) {
  return clip(o, r, p, v);
}

std::vector<double> processed_curvature(const HalfedgeMesh& mesh, double radius, double maxdim,
                                        CurvatureVariant variant, int threads) {
  const auto n = static_cast<std::int64_t>(mesh.positions.size());
  std::vector<double> curvature(mesh.positions.size(), 0.0);
#pragma omp parallel num_threads(threads)
  {
    WalkScratch scratch;
#pragma omp for schedule(dynamic, 512)
    for (std::int64_t v = 0; v < n; ++v) {
      const Tensor t = vertex_tensor(mesh, static_cast<std::uint32_t>(v), radius, variant, scratch);
      curvature[v] = curvature_of(t, maxdim);
    }
  }
  return curvature;
}

std::vector<std::vector<double>> processed_curvatures(const HalfedgeMesh& mesh,
                                                      const std::vector<double>& radii,
                                                      double maxdim, CurvatureVariant variant,
                                                      int threads, LoopProgress* progress) {
  if (!std::is_sorted(radii.begin(), radii.end())) {
    throw std::invalid_argument("processed_curvatures: the radii must not decrease");
  }
  const auto n = static_cast<std::int64_t>(mesh.positions.size());
  std::vector<std::vector<double>> curvatures(radii.size(),
                                              std::vector<double>(mesh.positions.size()));
#pragma omp parallel num_threads(threads)
  {
    MultiWalkScratch scratch;
    std::vector<Tensor> tensors(radii.size());
#pragma omp for schedule(dynamic, 512)
    for (std::int64_t v = 0; v < n; ++v) {
      vertex_tensors(mesh, static_cast<std::uint32_t>(v), radii, variant, scratch, tensors);
      for (std::size_t j = 0; j < radii.size(); ++j)
        curvatures[j][v] = curvature_of(tensors[j], maxdim);
      if (progress) progress->add();
    }
  }
  return curvatures;
}

}  // namespace qm3d::mesh::detail
