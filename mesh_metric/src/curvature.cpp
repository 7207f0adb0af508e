#include "curvature.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>

#include "vec3_ops.h"
#include "walk_scratch.h"

namespace qm3d::mesh::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;

// MEPP2's asin: the sine is clamped to [-1, 1] first.
double asin_clamped(double s) { return std::asin(std::clamp(s, -1.0, 1.0)); }

bool face_collapsed(const HalfedgeMesh& m, std::int32_t f) {
  const Triangle& t = m.triangles[f];
  return m.positions[t[0]] == m.positions[t[1]] && m.positions[t[1]] == m.positions[t[2]];
}

// MEPP2's search for a usable neighbouring face when one of the two faces of an edge is
// collinear (NaN normal), curvature_cmdm.hpp "Case 2" / "Case 3". Half-edge k is (w -> v).
// Returns the dihedral angle or 0 when no face is found.
double beta_with_replacement(const HalfedgeMesh& m, std::uint32_t v, std::uint32_t k,
                             const Vec3& vec, double len, bool replace_second) {
  const VertexRings& r = m.rings;
  const std::uint32_t w = r.source[k];
  const std::int32_t kept_face = replace_second ? r.face[k] : r.opposite_face[k];
  const Vec3& kept = m.face_normals[kept_face];
  Vec3 destination = m.positions[v];
  std::vector<std::uint32_t> stack{w};
  std::vector<std::uint32_t> seen{w};
  while (!stack.empty()) {
    const std::uint32_t t = stack.back();
    stack.pop_back();
    for (std::uint32_t k2 = r.begin(t); k2 < r.end(t); ++k2) {
      const std::uint32_t s = r.source[k2];
      if (m.positions[s] != destination) continue;
      const std::int32_t nf = r.face[k2];
      if (nf == kNoFace) continue;
      const Vec3& n = m.face_normals[nf];
      if (!has_nan(n) && nf != kept_face) {
        const Vec3 cp = replace_second ? cross(kept, n) : cross(n, kept);
        return asin_clamped(dot(cp, vec) / len);
      }
      if (std::find(seen.begin(), seen.end(), s) == seen.end()) {
        stack.push_back(s);
        seen.push_back(s);
      }
    }
    destination = m.positions[w];
  }
  return 0.0;
}

// Signed dihedral angle of the edge of half-edge k, as MEPP2 computes it (SPEC-CMDM 1.5 step 4);
// NaN when the edge must be skipped (a collapsed face).
double edge_beta(const HalfedgeMesh& m, std::uint32_t v, std::uint32_t k, const Vec3& vec,
                 double len) {
  const std::int32_t f1 = m.rings.face[k], f2 = m.rings.opposite_face[k];
  if (face_collapsed(m, f1) || face_collapsed(m, f2)) return std::numeric_limits<double>::quiet_NaN();
  const Vec3& n1 = m.face_normals[f1];
  const Vec3& n2 = m.face_normals[f2];
  const bool nan1 = has_nan(n1), nan2 = has_nan(n2);
  if (!nan1 && !nan2) {
    const double cosine = dot(n1, n2) / std::sqrt(dot(n1, n1) * dot(n2, n2));
    if (cosine == -1) return 0.0;  // opposite normals: MEPP2's shadowed `beta = pi/2` leaves 0
    return asin_clamped(dot(cross(n1, n2), vec) / len);
  }
  if (nan1 && nan2) return 0.0;
  return beta_with_replacement(m, v, k, vec, len, /*replace_second=*/nan2);
}

void add_edge_tensor(double tensor[3][3], const Vec3& vec, double coeff) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) tensor[i][j] += vec[i] * vec[j] * coeff;
  }
}

// Accumulates the curvature tensor of vertex v0 within the ball of radius r.
void vertex_tensor(const HalfedgeMesh& m, std::uint32_t v0, double r, CurvatureVariant variant,
                   WalkScratch& scratch, double tensor[3][3]) {
  const VertexRings& rings = m.rings;
  const Vec3& o = m.positions[v0];
  scratch.start(m.positions.size());
  scratch.visit(v0);
  scratch.stack.push_back(v0);
  while (!scratch.stack.empty()) {
    const std::uint32_t v = scratch.stack.back();
    scratch.stack.pop_back();
    const Vec3& p = m.positions[v];
    const Vec3 p_minus_o = sub(p, o);
    for (std::uint32_t k = rings.begin(v); k < rings.end(v); ++k) {
      const std::uint32_t w = rings.source[k];
      Vec3 vec = sub(m.positions[w], p);
      const double along = dot(vec, p_minus_o);
      const bool outward = variant == CurvatureVariant::kCmdm ? along >= 0.0 : along > 0.0;
      if (v != v0 && !outward) continue;
      const bool isect = sphere_clip_vector(o, r, p, vec);
      const bool border = rings.face[k] == kNoFace || rings.opposite_face[k] == kNoFace;
      const bool contributes = variant == CurvatureVariant::kCmdm ? isect : true;
      if (!border && contributes) {
        const double len = norm(vec);
        if (len > 0) {
          const double beta = edge_beta(m, v, k, vec, len);
          if (!std::isnan(beta)) add_edge_tensor(tensor, vec, beta / len);
        }
      }
      if (!isect && scratch.visit(w)) scratch.stack.push_back(w);
    }
  }
  const double area = kPi * r * r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) tensor[i][j] /= area;
  }
}

// maxdim * (|l0| + |l1|) / 2 with l0, l1 the eigenvalues of largest magnitude.
double post_process(const double tensor[3][3], double maxdim) {
  Eigen::Matrix3d t;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) t(i, j) = tensor[i][j];
  }
  Eigen::Vector3d values;
  if (t(0, 1) == 0 && t(0, 2) == 0 && t(1, 0) == 0 && t(1, 2) == 0 && t(2, 0) == 0 && t(2, 1) == 0) {
    values = t.diagonal();
  } else {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(t, Eigen::EigenvaluesOnly);
    if (solver.info() != Eigen::Success) return 0.0;
    values = solver.eigenvalues();
  }
  double mags[3] = {std::fabs(values[0]), std::fabs(values[1]), std::fabs(values[2])};
  std::sort(mags, mags + 3, [](double a, double b) { return a > b; });
  return (mags[0] * maxdim + mags[1] * maxdim) / 2.0;
}

}  // namespace

bool sphere_clip_vector(const Vec3& o, double r, const Vec3& p, Vec3& v) {
  const Vec3 w = sub(p, o);
  const double a = dot(v, v);
  if (std::fabs(a) < std::numeric_limits<double>::epsilon()) return false;
  const double b = 2.0 * dot(v, w);
  const double c = dot(w, w) - r * r;
  const double delta = b * b - 4. * a * c;
  if (delta < 0.) return true;  // numerical noise: treated as crossing, unclipped
  const double t = (-b + std::sqrt(delta)) / (2.0 * a);
  if (t >= 1.) return false;  // the far end is inside the sphere
  v = scale(v, t);
  return true;
}

std::vector<double> processed_curvature(const HalfedgeMesh& mesh, double radius, double maxdim,
                                        CurvatureVariant variant) {
  const auto n = static_cast<std::int64_t>(mesh.positions.size());
  std::vector<double> curvature(mesh.positions.size(), 0.0);
#pragma omp parallel
  {
    WalkScratch scratch;
#pragma omp for schedule(dynamic, 512)
    for (std::int64_t v = 0; v < n; ++v) {
      double tensor[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
      vertex_tensor(mesh, static_cast<std::uint32_t>(v), radius, variant, scratch, tensor);
      curvature[v] = post_process(tensor, maxdim);
    }
  }
  return curvature;
}

}  // namespace qm3d::mesh::detail
