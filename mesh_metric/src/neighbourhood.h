// The edge-intersection neighbourhood of a vertex and its image on the other mesh
// (MEPP2 process_cmdm_per_vertex, SPEC-CMDM 1.7), turned into weighted paired samples. Internal.
#pragma once

#include <cstdint>
#include <vector>

#include "halfedge_mesh.h"
#include "qm3d/common/color.h"
#include "qm3d/common/features.h"
#include "walk_scratch.h"

namespace qm3d::mesh::detail {

/// Per-vertex fields of the iterated mesh (side 1) and their values at the matched points on the
/// other mesh (side 2). `color` / `color_match` may be null when only curvature is sampled.
struct MatchedFields {
  const HalfedgeMesh* mesh = nullptr;
  const std::vector<Vec3>* matched_point = nullptr;
  const std::vector<double>* curvature = nullptr;
  const std::vector<double>* curvature_match = nullptr;
  const std::vector<Lab>* color = nullptr;  ///< LAB2000HL
  const std::vector<Lab>* color_match = nullptr;
};

struct WalkParameters {
  double radius = 0;                ///< neighbourhood radius h
  double sigma = 0;                 ///< Gaussian sigma of the weights
  bool strict_outward_test = false; ///< MSDM2 ">", CMDM ">="
};

/// MEPP2's sphere_clip_vector_cmdm (cmdm.h): like sphere_clip_vector but a = 0, delta < 0 and
/// t < 0 all mean "crossing, unclipped", and t < 1e-16 becomes t = 0.01.
bool sphere_clip_vector_cmdm(const Vec3& o, double r, const Vec3& p, Vec3& v);
/// The same, also giving the clip parameter t (v becomes t v; t = 1 when v is not clipped).
bool sphere_clip_vector_cmdm(const Vec3& o, double r, const Vec3& p, Vec3& v, double& t);

/// Fills `out` with the samples of vertex v0's neighbourhood: v0 itself, every vertex reached
/// inside the ball (once), and one interpolated point per edge crossing the sphere, each paired
/// with its image on the other mesh, with Gaussian weights w1 = G(|P1 - p(v0)|) and
/// w2 = G(|P2 - q(v0)|). MEPP2's walk as it is written, one radius at a time; the metrics use
/// sample_neighbourhoods, which gives the same samples (in another order), and the tests check
/// one against the other.
void sample_neighbourhood(const MatchedFields& fields, std::uint32_t v0, const WalkParameters& walk,
                          WalkScratch& scratch, NeighbourhoodSamples& out);

/// The samples of v0's neighbourhoods at several radii in one walk: out[j] holds exactly the
/// samples sample_neighbourhood(levels[j], v0, walks[j]) gives (the same values, bit for bit),
/// in another order. `levels[j]` are the fields at scale j (they differ only by curvature);
/// `walks[j].radius` must increase with j.
///
/// One walk serves every radius (walk_outward_levels says why): an entered vertex's sample goes
/// into every level from its entry level on; a crossing at r_j gives a sample at level j only.
/// The sample order, v0 first and then as found, is not MEPP2's depth-first order at each
/// radius, so sums over the samples may differ by rounding (the numeric contract,
/// DEVELOPERS.md).
void sample_neighbourhoods(const std::vector<MatchedFields>& levels, std::uint32_t v0,
                           const std::vector<WalkParameters>& walks, MultiWalkScratch& scratch,
                           std::vector<NeighbourhoodSamples>& out);

}  // namespace qm3d::mesh::detail
