#include "neighbourhood.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <cmath>

#include "qm3d/common/statistics.h"
#include "vec3_ops.h"

namespace qm3d::mesh::detail {
namespace {

// MEPP2's replacement for a vanishing clip parameter (cmdm.h: `if(t < 1.e-16) t = 0.01;`).
constexpr double kTinyClipParameter = 1e-16;
constexpr double kTinyClipReplacement = 0.01;

// One sample: its position, curvature and colour on each side.
struct Sample {
  Vec3 point1, point2;
  double curv1 = 0, curv2 = 0;
  Lab color1, color2;
};

Lab blend(const Lab& a, const Lab& b, double t) {
  return {(1 - t) * a.L + t * b.L, (1 - t) * a.a + t * b.a, (1 - t) * a.b + t * b.b};
}

Sample vertex_sample(const MatchedFields& f, std::uint32_t v) {
  Sample s;
  s.point1 = f.mesh->positions[v];
  s.point2 = (*f.matched_point)[v];
  s.curv1 = (*f.curvature)[v];
  s.curv2 = (*f.curvature_match)[v];
  if (f.color) {
    s.color1 = (*f.color)[v];
    s.color2 = (*f.color_match)[v];
  }
  return s;
}

// The point where edge (v -> w) leaves the sphere: position v + clipped, attributes blended with
// t, the clip parameter (clipped = t edge). MEPP2 computes t again from the two lengths,
// |clipped| / |edge|: the same number to rounding (|fl(t e)| / |e| is t within a few ulp; exactly
// 1 for an unclipped crossing, where both lengths are |edge|), taken here without the two square
// roots and the division (about a tenth of the neighbourhood walk's time). A sample's values may
// differ from the two-length ones in their last bits; both the one-walk and the per-radius walk
// take t so, and the scores stay within 1e-13 relative (residues of an exact 0, on identical
// geometry, within 1e-16 absolute).
__attribute__((always_inline)) inline Sample crossing_sample(const MatchedFields& f,
                                                             std::uint32_t v, std::uint32_t w,
                                                             const Vec3& clipped, double t) {
  const auto& q = *f.matched_point;
  Sample s;
  s.point1 = add(f.mesh->positions[v], clipped);
  s.point2 = add(q[v], scale(sub(q[w], q[v]), t));
  s.curv1 = (1 - t) * (*f.curvature)[v] + t * (*f.curvature)[w];
  s.curv2 = (1 - t) * (*f.curvature_match)[v] + t * (*f.curvature_match)[w];
  if (f.color) {
    s.color1 = blend((*f.color)[v], (*f.color)[w], t);
    s.color2 = blend((*f.color_match)[v], (*f.color_match)[w], t);
  }
  return s;
}

// The squared distance |a - b|^2.
double squared_distance(const Vec3& a, const Vec3& b) {
  const Vec3 d = sub(a, b);
  return dot(d, d);
}

// The colour terms of a sample before their square roots: chroma(c)^2 = a^2 + b^2 on each side
// and hue_difference's (a1 - a2)^2 + (b1 - b2)^2, each written as chroma and hue_difference
// write it. finish_colours takes the roots once the walk is done, two samples at a time.
struct ColourSquares {
  double chroma1 = 0, chroma2 = 0, hue = 0;
};

ColourSquares colour_squares(const Lab& c1, const Lab& c2) {
  return {c1.a * c1.a + c1.b * c1.b, c2.a * c2.a + c2.b * c2.b,
          std::pow(c1.a - c2.a, 2) + std::pow(c1.b - c2.b, 2)};
}

// chroma1 = sqrt(chroma1), chroma2 = sqrt(chroma2) and hue_diff = sqrt(hue_diff - (chroma1 -
// chroma2)^2), or 0 where that is negative: chroma() and hue_difference() operation for
// operation (IEEE square roots, differences and products round the same in SSE2's two lanes as
// in scalar code), for the samples' colour terms left by colour_squares.
void finish_colours(NeighbourhoodSamples& out) {
  const std::size_t n = out.chroma1.size();
  double *c1 = out.chroma1.data(), *c2 = out.chroma2.data(), *h = out.hue_diff.data();
  std::size_t i = 0;
#if defined(__SSE2__)
  const __m128d zero = _mm_setzero_pd();
  for (; i + 2 <= n; i += 2) {
    const __m128d r1 = _mm_sqrt_pd(_mm_loadu_pd(c1 + i));
    const __m128d r2 = _mm_sqrt_pd(_mm_loadu_pd(c2 + i));
    const __m128d dc = _mm_sub_pd(r1, r2);
    const __m128d dh2 = _mm_sub_pd(_mm_loadu_pd(h + i), _mm_mul_pd(dc, dc));
    // dh2 < 0 ? 0 : sqrt(dh2): the root where "not less than 0" holds, else +0.
    const __m128d root = _mm_and_pd(_mm_cmpnlt_pd(dh2, zero), _mm_sqrt_pd(dh2));
    _mm_storeu_pd(c1 + i, r1);
    _mm_storeu_pd(c2 + i, r2);
    _mm_storeu_pd(h + i, root);
  }
#endif
  for (; i < n; ++i) {
    c1[i] = std::sqrt(c1[i]);
    c2[i] = std::sqrt(c2[i]);
    const double dc = c1[i] - c2[i];
    const double dh2 = h[i] - std::pow(dc, 2);
    h[i] = dh2 < 0 ? 0.0 : std::sqrt(dh2);
  }
}

// w1 and w2 hold the samples' squared distances until the walk is done; to_weights turns them
// into the Gaussian weights of one level in a vectorised pass. MEPP2 takes the distance's square
// root and squares it again in the weight: the same number to rounding, without a square root
// per sample and side (scores within 1e-13 relative).
__attribute__((always_inline)) inline void push_sample(const Sample& s, const Vec3& center1,
                                                       const Vec3& center2, bool with_color,
                                                       NeighbourhoodSamples& out) {
  out.w1.push_back(squared_distance(s.point1, center1));
  out.w2.push_back(squared_distance(s.point2, center2));
  out.curv1.push_back(s.curv1);
  out.curv2.push_back(s.curv2);
  if (!with_color) return;
  out.light1.push_back(s.color1.L);
  out.light2.push_back(s.color2.L);
  const ColourSquares c = colour_squares(s.color1, s.color2);
  out.chroma1.push_back(c.chroma1);
  out.chroma2.push_back(c.chroma2);
  out.hue_diff.push_back(c.hue);
}

// A vertex sample at several levels: the distances, colours and the colour terms do not depend
// on the level, so they are computed once (the same operations as push_sample).
void push_vertex_levels(const std::vector<MatchedFields>& levels, std::size_t first,
                        std::uint32_t w, const Vec3& center1, const Vec3& center2, bool with_color,
                        std::vector<NeighbourhoodSamples>& out) {
  const MatchedFields& f = levels.front();
  const double d1 = squared_distance(f.mesh->positions[w], center1);
  const double d2 = squared_distance((*f.matched_point)[w], center2);
  Lab c1, c2;
  ColourSquares squares;
  if (with_color) {
    c1 = (*f.color)[w];
    c2 = (*f.color_match)[w];
    squares = colour_squares(c1, c2);
  }
  for (std::size_t j = first; j < levels.size(); ++j) {
    NeighbourhoodSamples& o = out[j];
    o.w1.push_back(d1);
    o.w2.push_back(d2);
    o.curv1.push_back((*levels[j].curvature)[w]);
    o.curv2.push_back((*levels[j].curvature_match)[w]);
    if (!with_color) continue;
    o.light1.push_back(c1.L);
    o.light2.push_back(c2.L);
    o.chroma1.push_back(squares.chroma1);
    o.chroma2.push_back(squares.chroma2);
    o.hue_diff.push_back(squares.hue);
  }
}

void to_weights(NeighbourhoodSamples& out, double sigma) {
  finish_colours(out);
  gaussian_weights_from_squares_in_place(out.w1.data(), out.w1.size(), sigma);
  gaussian_weights_from_squares_in_place(out.w2.data(), out.w2.size(), sigma);
}

}  // namespace

namespace {

// sphere_clip_vector_cmdm's test, inlined into the walks (called out of line, the test and its
// call took about a fifth of the neighbourhood walk's time).
__attribute__((always_inline)) inline bool clip_cmdm(const Vec3& o, double r, const Vec3& p,
                                                     Vec3& v, double& t_out) {
  t_out = 1.0;
  const Vec3 w = sub(p, o);
  const double a = dot(v, v);
  if (far_end_clearly_inside(w, v, a, r)) return false;  // what t >= 1 below returns
  const double b = 2.0 * dot(v, w);
  const double c = dot(w, w) - r * r;
  const double delta = b * b - 4 * a * c;
  if (a == 0) return true;
  if (delta < 0) return true;
  double t = (-b + std::sqrt(delta)) / (2.0 * a);
  if (t < 0.0) return true;
  if (t >= 1.0) return false;
  if (t < kTinyClipParameter) t = kTinyClipReplacement;
  v = scale(v, t);
  t_out = t;
  return true;
}

}  // namespace

bool sphere_clip_vector_cmdm(const Vec3& o, double r, const Vec3& p, Vec3& v) {
  double t;
  return clip_cmdm(o, r, p, v, t);
}

bool sphere_clip_vector_cmdm(const Vec3& o, double r, const Vec3& p, Vec3& v, double& t_out) {
  return clip_cmdm(o, r, p, v, t_out);
}

void sample_neighbourhood(const MatchedFields& f, std::uint32_t v0, const WalkParameters& walk,
                          WalkScratch& scratch, NeighbourhoodSamples& out) {
  const HalfedgeMesh& m = *f.mesh;
  const bool with_color = f.color != nullptr;
  const Vec3& o = m.positions[v0];
  const Vec3& q0 = (*f.matched_point)[v0];
  out.clear();
  push_sample(vertex_sample(f, v0), o, q0, with_color, out);
  walk_outward(m, v0, walk.strict_outward_test, scratch,
               [&](std::uint32_t v, std::uint32_t, std::uint32_t w, const Vec3& edge) {
                 Vec3 vec = edge;
                 double t;
                 const bool isect = clip_cmdm(o, walk.radius, m.positions[v], vec, t);
                 if (!isect && !scratch.enter(w)) return;  // inside and already sampled
                 // A zero-length crossing edge gives the vertex sample.
                 const Sample s = (isect && dot(edge, edge) != 0) ? crossing_sample(f, v, w, vec, t)
                                                                  : vertex_sample(f, w);
                 push_sample(s, o, q0, with_color, out);
               });
  to_weights(out, walk.sigma);
}

void sample_neighbourhoods(const std::vector<MatchedFields>& levels, std::uint32_t v0,
                           const std::vector<WalkParameters>& walks, MultiWalkScratch& scratch,
                           std::vector<NeighbourhoodSamples>& out) {
  const MatchedFields& f = levels.front();
  const HalfedgeMesh& m = *f.mesh;
  const bool with_color = f.color != nullptr;
  const bool strict = walks.front().strict_outward_test;
  const Vec3& o = m.positions[v0];
  const Vec3& q0 = (*f.matched_point)[v0];
  out.resize(levels.size());
  for (NeighbourhoodSamples& s : out) s.clear();
  push_vertex_levels(levels, 0, v0, o, q0, with_color, out);
  walk_outward_levels(
      m, v0, strict, levels.size(), scratch,
      [&](std::size_t level, std::uint32_t v, std::uint32_t, std::uint32_t w, const Vec3& edge) {
        Vec3 vec = edge;
        double t;
        if (!clip_cmdm(o, walks[level].radius, m.positions[v], vec, t)) {
          if (scratch.enter(w)) push_vertex_levels(levels, level, w, o, q0, with_color, out);
          return false;
        }
        // A crossing: a sample at this level only (a zero-length edge gives w's vertex sample).
        const MatchedFields& here = levels[level];
        const Sample s =
            dot(edge, edge) != 0 ? crossing_sample(here, v, w, vec, t) : vertex_sample(here, w);
        push_sample(s, o, q0, with_color, out[level]);
        return true;
      },
      [](std::size_t) {});
  for (std::size_t j = 0; j < out.size(); ++j) to_weights(out[j], walks[j].sigma);
}

}  // namespace qm3d::mesh::detail
