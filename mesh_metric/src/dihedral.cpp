#include "dihedral.h"

#include <algorithm>
#include <cmath>

#include "vec3_ops.h"

namespace qm3d::mesh::detail {
namespace {

// MEPP2's asin: the sine is clamped to [-1, 1] first.
double asin_clamped(double s) { return std::asin(std::clamp(s, -1.0, 1.0)); }

bool face_collapsed(const DihedralInput& m, std::int32_t f) {
  const Triangle& t = m.triangles[f];
  return m.positions[t[0]] == m.positions[t[1]] && m.positions[t[1]] == m.positions[t[2]];
}

// MEPP2's search for a usable neighbouring face when one of the two faces of an edge is
// collinear (NaN normal), curvature_cmdm.hpp "Case 2" / "Case 3". Half-edge k is (w -> v).
// Returns the dihedral angle or 0 when no face is found.
double beta_with_replacement(const DihedralInput& m, std::uint32_t v, std::uint32_t k,
                             const Vec3& vec, double len, bool replace_second) {
  const RingFaces& r = m.rings;
  const std::uint32_t w = r.source[k];
  const std::int32_t kept_face = replace_second ? r.face[k] : r.opposite_face[k];
  const Vec3& kept = m.face_normals[kept_face];
  Vec3 destination = m.positions[v];
  std::vector<std::uint32_t> stack{w};
  std::vector<std::uint32_t> seen{w};
  while (!stack.empty()) {
    const std::uint32_t t = stack.back();
    stack.pop_back();
    for (std::uint32_t k2 = r.offsets[t]; k2 < r.offsets[t + 1]; ++k2) {
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

// Signed dihedral angle of the edge of half-edge k (length len > 0), as curvature_cmdm.hpp
// computes it (SPEC-CMDM 1.5 step 4); kNoContribution when the edge must be skipped (a collapsed
// face).
double repaired_beta(const DihedralInput& m, std::uint32_t v, std::uint32_t k, const Vec3& vec,
                     double len) {
  const std::int32_t f1 = m.rings.face[k], f2 = m.rings.opposite_face[k];
  if (face_collapsed(m, f1) || face_collapsed(m, f2)) return kNoContribution;
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

// The same angle as MEPP2's generic curvature.hpp computes it, with no special case: where that
// code gets NaN (a zero-length edge: 0 / 0; a NaN face normal), kVoidsTensor.
double generic_beta(const DihedralInput& m, std::uint32_t k, const Vec3& vec, double len) {
  const Vec3& n1 = m.face_normals[m.rings.face[k]];
  const Vec3& n2 = m.face_normals[m.rings.opposite_face[k]];
  if (len == 0 || has_nan(n1) || has_nan(n2)) return kVoidsTensor;
  return asin_clamped(dot(cross(n1, n2), vec) / len);
}

double edge_beta(const DihedralInput& m, DegenerateEdges rule, std::uint32_t v, std::uint32_t k) {
  const Vec3 edge = sub(m.positions[m.rings.source[k]], m.positions[v]);
  const double len = norm(edge);
  if (rule == DegenerateEdges::kVoidTensor) return generic_beta(m, k, edge, len);
  // A zero-length edge never crosses the sphere, so curvature_cmdm.hpp never uses its angle.
  return len > 0 ? repaired_beta(m, v, k, edge, len) : 0.0;
}

// The half-edge (v -> w) of the edge that k = (w -> v) runs along, with the faces swapped;
// kNoTwin when there is none (a border, or several edges between v and w).
constexpr std::uint32_t kNoTwin = 0xffffffffu;

std::uint32_t twin(const RingFaces& r, std::uint32_t v, std::uint32_t k) {
  const std::uint32_t w = r.source[k];
  std::uint32_t found = kNoTwin;
  for (std::uint32_t k2 = r.offsets[w]; k2 < r.offsets[w + 1]; ++k2) {
    if (r.source[k2] != v || r.face[k2] != r.opposite_face[k] || r.opposite_face[k2] != r.face[k]) {
      continue;
    }
    if (found != kNoTwin) return kNoTwin;
    found = k2;
  }
  return found;
}

}  // namespace

// An edge's two half-edges get the same angle wherever both faces have a normal: the twin's
// vector is the exact negation of this one's and its faces are swapped, so (n2 x n1) . (-v) and
// |-v| are the same numbers as (n1 x n2) . v and |v| bit for bit (the cosine test too), under
// either rule. Each edge's angle is therefore computed once, on the half-edge entering its
// smaller vertex, and copied onto the twin; only next to NaN normals (MEPP2's replacement walk
// is not symmetric) and where the twin is not unique is the twin computed on its own.
std::vector<double> dihedral_angles(const DihedralInput& m, DegenerateEdges rule, int threads) {
  const RingFaces& r = m.rings;
  std::vector<double> beta(r.source.size(), kNoContribution);
  const auto n = static_cast<std::int64_t>(r.offsets.size()) - 1;
  const auto interior = [&](std::uint32_t k) {
    return r.face[k] != kNoFace && r.opposite_face[k] != kNoFace;  // else a border edge
  };
#pragma omp parallel num_threads(threads)
  {
#pragma omp for schedule(dynamic, 1024)
    for (std::int64_t vi = 0; vi < n; ++vi) {
      const auto v = static_cast<std::uint32_t>(vi);
      for (std::uint32_t k = r.offsets[v]; k < r.offsets[v + 1]; ++k) {
        if (interior(k) && v < r.source[k]) beta[k] = edge_beta(m, rule, v, k);
      }
    }
#pragma omp for schedule(dynamic, 1024)
    for (std::int64_t vi = 0; vi < n; ++vi) {
      const auto v = static_cast<std::uint32_t>(vi);
      for (std::uint32_t k = r.offsets[v]; k < r.offsets[v + 1]; ++k) {
        if (!interior(k) || v < r.source[k]) continue;
        const std::uint32_t k2 = v > r.source[k] ? twin(r, v, k) : kNoTwin;
        const bool both_normals =
            !has_nan(m.face_normals[r.face[k]]) && !has_nan(m.face_normals[r.opposite_face[k]]);
        beta[k] = k2 != kNoTwin && both_normals ? beta[k2] : edge_beta(m, rule, v, k);
      }
    }
  }
  return beta;
}

}  // namespace qm3d::mesh::detail
