// GeodesicPSIM's patches: the 1-ring of the vertex nearest a keypoint in each mesh, shrunk to a
// common size, and their features: colour smoothness on the patch graph, discrete mean curvature
// and texel statistics (SPEC-GEODESICPSIM steps 6-8; Yang et al., arXiv:2308.04928, Sec. 3).
// Reference: Qi-Yangsjtu/GeodesicPSIM @ 3e06453; each rule that decides a digit is the
// reference's, as the comments say.
#include <algorithm>
#include <cmath>

#include "geodesicpsim_internal.h"
#include "qm3d/common/error.h"

namespace qm3d::mesh::gpsim {
namespace {

/// The reference's small constant in the graph's radius and degree normalisation.
constexpr double kGraphEps = 1e-6;
/// In-triangle tolerance of the texel rasterisation (float32 areas), the reference's 0.1.
constexpr double kInsideTolerance = 1e-1;

using Yuv = std::array<double, 3>;

struct Patch {
  std::vector<P3> v;   // current (shrunk) positions, in ascending global vertex order
  std::vector<Tri> f;  // local vertex indices, faces in ascending global order
  std::vector<P2> uv;  // the patch's UVs as read (ascending global UV order)
  std::vector<Tri> ft;
  int centre = 0;
  double shift = 0;                        // distance from the keypoint to the centre vertex
  std::vector<std::array<P2, 3>> face_uv;  // each face's corner UVs after the last shrink
  std::vector<Yuv> colour;                 // each vertex's colour after the last shrink
};

int local_index(const std::vector<int>& sorted, int global) {
  return static_cast<int>(std::lower_bound(sorted.begin(), sorted.end(), global) - sorted.begin());
}

// The faces around the vertex nearest the keypoint, renumbered (SPEC step 6).
Patch make_patch(const PatchSource& s, const P3& keypoint) {
  Patch p;
  const int c = s.nearest->nearest(keypoint, p.shift);
  std::vector<int> vs, ts;
  for (int k = s.face_offsets[c]; k < s.face_offsets[c + 1]; ++k) {
    const int f = s.faces[k];
    for (int j = 0; j < 3; ++j) {
      vs.push_back(s.mesh->f[f][j]);
      ts.push_back(s.mesh->ft[f][j]);
    }
  }
  std::sort(vs.begin(), vs.end());
  vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
  std::sort(ts.begin(), ts.end());
  ts.erase(std::unique(ts.begin(), ts.end()), ts.end());
  for (int v : vs) p.v.push_back(s.mesh->v[v]);
  for (int t : ts) p.uv.push_back(s.mesh->uv[t]);
  for (int k = s.face_offsets[c]; k < s.face_offsets[c + 1]; ++k) {
    const int f = s.faces[k];
    Tri a, t;
    for (int j = 0; j < 3; ++j) {
      a[j] = local_index(vs, s.mesh->f[f][j]);
      t[j] = local_index(ts, s.mesh->ft[f][j]);
    }
    p.f.push_back(a);
    p.ft.push_back(t);
  }
  p.centre = local_index(vs, c);
  return p;
}

// ---- Texels ----------------------------------------------------------------------------------

// The reference's UV -> texel coordinate: (int)(t + 0.5) (truncation), 0 -> 1, clamped to max.
int texel_coordinate(double t, int max) {
  // Far outside the image (UVs beyond a single wrap) the int cast would overflow: bounded first.
  constexpr double kFar = 1 << 30;
  int value = static_cast<int>(std::clamp(t + 0.5, -kFar, kFar));
  if (value == 0) value = 1;
  return value > max ? max : value;
}

// 1-based texel coordinates (x down the rows, y along the columns) of a UV.
std::array<int, 2> texel_of(const P2& uv, const GpTexture& tex) {
  return {texel_coordinate((1 - uv[1]) * tex.height, tex.height),
          texel_coordinate(uv[0] * tex.width, tex.width)};
}

// The texel's YUV. The reference goes through the linear index (x - 1) W + y and splits it
// back as row = index / W, col = index - row W - 1: y == W lands on (x, 0), the next row's first
// texel (the column-W quirk); rows and columns are clamped.
Yuv texel_yuv(int x, int y, const GpTexture& tex) {
  const int w = tex.width, h = tex.height;
  const int index = std::clamp((x - 1) * w + y, 1, w * h);
  const int row = std::clamp(index / w, 0, h - 1);
  const int col = std::clamp(index - row * w - 1, 0, w - 1);
  const std::uint8_t* c = &tex.rgb[3 * (static_cast<std::size_t>(row) * w + col)];
  const double r = c[0], g = c[1], b = c[2];
  // The reference's YUV matrix (BT.601 with 128 offsets, no rounding).
  return {r * 0.299 + g * 0.587 + b * 0.114, r * -0.1678 + g * -0.3313 + b * 0.5 + 128,
          r * 0.5 + g * -0.4187 + b * -0.0813 + 128};
}

// ---- Shrinking (SPEC step 7) -----------------------------------------------------------------

// Each vertex's colour: the mean YUV of the texels at its corners' UVs (faces, then corners, in
// order).
void vertex_colours(Patch& p, const GpTexture& tex) {
  p.colour.assign(p.v.size(), Yuv{0, 0, 0});
  for (std::size_t i = 0; i < p.v.size(); ++i) {
    Yuv sum{0, 0, 0};
    int n = 0;
    for (std::size_t f = 0; f < p.f.size(); ++f) {
      for (int k = 0; k < 3; ++k) {
        if (p.f[f][k] != static_cast<int>(i)) continue;
        const auto t = texel_of(p.face_uv[f][k], tex);
        const Yuv c = texel_yuv(t[0], t[1], tex);
        for (int d = 0; d < 3; ++d) sum[d] += c[d];
        ++n;
      }
    }
    for (int d = 0; d < 3; ++d) p.colour[i][d] = sum[d] / n;
  }
}

// Shrinks the patch toward its centre by `scale`: positions from the current ones (shrinks
// compose), each face's UVs from the UVs as read toward the centre corner's UV (the last shrink
// wins: the reference's quirk), then the vertex colours.
void shrink(Patch& p, double scale, const GpTexture& tex) {
  const P3 c = p.v[p.centre];
  for (P3& v : p.v) {
    for (int d = 0; d < 3; ++d) v[d] = (v[d] - c[d]) / scale + c[d];
  }
  p.face_uv.resize(p.f.size());
  for (std::size_t f = 0; f < p.f.size(); ++f) {
    int centre_corner = 0;
    for (int k = 0; k < 3; ++k) {
      if (p.f[f][k] == p.centre) centre_corner = k;
    }
    const P2 cu = p.uv[p.ft[f][centre_corner]];
    for (int k = 0; k < 3; ++k) {
      const P2& u = p.uv[p.ft[f][k]];
      p.face_uv[f][k] = k == centre_corner
                            ? cu
                            : P2{cu[0] + (u[0] - cu[0]) / scale, cu[1] + (u[1] - cu[1]) / scale};
    }
  }
  vertex_colours(p, tex);
}

// The patch's edges: the ordered pairs (c0,c1), (c0,c2), (c1,c2) of its faces, unique, sorted.
std::vector<std::pair<int, int>> patch_edges(const Patch& p) {
  std::vector<std::pair<int, int>> e;
  for (const Tri& f : p.f) {
    e.emplace_back(f[0], f[1]);
    e.emplace_back(f[0], f[2]);
    e.emplace_back(f[1], f[2]);
  }
  std::sort(e.begin(), e.end());
  e.erase(std::unique(e.begin(), e.end()), e.end());
  return e;
}

double length(const P3& a, const P3& b) {
  const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

// The patch size: the mean of the centre's row of the edge-length matrix (zeros included).
double centre_mean_distance(const Patch& p) {
  const std::size_t n = p.v.size();
  std::vector<double> row(n, 0.0);
  for (const auto& [a, b] : patch_edges(p)) {
    if (a == p.centre) row[b] = length(p.v[a], p.v[b]);
    if (b == p.centre) row[a] = length(p.v[a], p.v[b]);
  }
  double sum = 0;
  for (double x : row) sum += x;
  return sum / static_cast<double>(n);
}

P3 cross(const P3& a, const P3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
P3 sub(const P3& a, const P3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double norm(const P3& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

// Each face's share of the patch area (before shrinking): the curvature normal's weights.
std::vector<double> area_weights(const Patch& p) {
  std::vector<double> w(p.f.size());
  double sum = 0;
  for (std::size_t f = 0; f < p.f.size(); ++f) {
    const Tri& t = p.f[f];
    w[f] = norm(cross(sub(p.v[t[0]], p.v[t[1]]), sub(p.v[t[2]], p.v[t[1]])));
    sum += w[f];
  }
  for (double& x : w) x /= sum;
  return w;
}

// Both patches brought to the size min(r_ref, r_dis), then both shrunk to `threshold` when
// larger; returns the final size (SPEC step 7).
double crop(Patch& ref, Patch& dis, const GpTexture& ref_tex, const GpTexture& dis_tex,
            double threshold) {
  const double ref_size = centre_mean_distance(ref), dis_size = centre_mean_distance(dis);
  const double scale = dis_size / ref_size;
  double size = ref_size;
  bool ref_done = false, dis_done = false;
  if (scale > 1) {
    shrink(dis, scale, dis_tex);
    dis_done = true;
  }
  if (scale < 1) {
    shrink(ref, 1 / scale, ref_tex);
    size = size * scale;
    ref_done = true;
  }
  if (size > threshold) {
    const double scale1 = size / threshold;
    shrink(ref, scale1, ref_tex);
    shrink(dis, scale1, dis_tex);
    size = threshold;
    ref_done = dis_done = true;
  }
  if (!ref_done) shrink(ref, 1, ref_tex);
  if (!dis_done) shrink(dis, 1, dis_tex);
  return size;
}

// ---- Features (SPEC step 8) ------------------------------------------------------------------

// |x^T L x| per channel, L = D^-1/2 (D - W) D^-1/2 the normalised Laplacian of the patch graph
// with Gaussian weights exp(-d / (2 mean(d) + eps)) (mean over the ordered edge list).
std::array<double, 3> colour_smoothness(const Patch& p) {
  const auto edges = patch_edges(p);
  const std::size_t n = p.v.size();
  std::vector<double> d(edges.size());
  double sum = 0;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    d[e] = length(p.v[edges[e].first], p.v[edges[e].second]);
    sum += d[e];
  }
  const double radius = sum / static_cast<double>(edges.size());
  std::vector<double> w(n * n, 0.0);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const double x = std::exp(-d[e] / (radius * 2.0 + kGraphEps));
    w[edges[e].first * n + edges[e].second] = x;
    w[edges[e].second * n + edges[e].first] = x;
  }
  std::vector<double> degree(n, 0.0), dinv(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) degree[i] += w[i * n + j];
    dinv[i] = 1 / std::sqrt(degree[i] + kGraphEps);
  }
  std::array<double, 3> out{};
  for (int c = 0; c < 3; ++c) {
    double total = 0;
    for (std::size_t j = 0; j < n; ++j) {
      double col = 0;  // (x^T L)_j
      for (std::size_t i = 0; i < n; ++i) {
        const double l = (i == j ? degree[i] - w[i * n + j] : -w[i * n + j]);
        col += p.colour[i][c] * (dinv[i] * l * dinv[j]);
      }
      total += col * p.colour[j][c];
    }
    out[c] = std::fabs(total);
  }
  return out;
}

// The reference's float32 triangle area on integer texel coordinates.
float triangle_area(double ax, double ay, double bx, double by, double cx, double cy) {
  return static_cast<float>(std::fabs((ax * (by - cy) + bx * (cy - ay) + cx * (ay - by)) / 2.0));
}

// Texels of the face's UV triangle: integer (x, y) in the box of its corners' texels whose three
// sub-triangle areas add up to its area within the tolerance (float32). Adds the face's mean and
// unbiased variance of Y, U, V to `stats` weighted later; returns the count.
int face_texels(const std::array<P2, 3>& uv, const GpTexture& tex, std::array<double, 6>& out) {
  std::array<std::array<int, 2>, 3> t;
  for (int k = 0; k < 3; ++k) t[k] = texel_of(uv[k], tex);
  const int x0 = std::min({t[0][0], t[1][0], t[2][0]}), x1 = std::max({t[0][0], t[1][0], t[2][0]});
  const int y0 = std::min({t[0][1], t[1][1], t[2][1]}), y1 = std::max({t[0][1], t[1][1], t[2][1]});
  const double ax = t[0][0], ay = t[0][1], bx = t[1][0], by = t[1][1], cx = t[2][0], cy = t[2][1];
  const float total = triangle_area(ax, ay, bx, by, cx, cy);
  // A face's texel box fits in the image when its UVs are in [0, 1]; UVs far outside it (beyond
  // what a single wrap brings back) would make the box huge.
  constexpr double kMaxBoxImages = 4;
  if (double(x1 - x0 + 1) * double(y1 - y0 + 1) > kMaxBoxImages * tex.width * tex.height + 16) {
    throw NumericError(
        "geodesicpsim: texture coordinates far outside [0, 1] (a face spans more "
        "than the texture image)");
  }
  std::vector<Yuv> texels;
  for (int x = x0; x <= x1; ++x) {
    for (int y = y0; y <= y1; ++y) {
      const float a1 = triangle_area(x, y, ax, ay, bx, by);
      const float a2 = triangle_area(x, y, bx, by, cx, cy);
      const float a3 = triangle_area(x, y, cx, cy, ax, ay);
      if (std::fabs(total - (a1 + a2 + a3)) < kInsideTolerance)
        texels.push_back(texel_yuv(x, y, tex));
    }
  }
  const auto n = static_cast<double>(texels.size());
  for (int c = 0; c < 3; ++c) {
    double sum = 0;
    for (const Yuv& y : texels) sum += y[c];
    const double mean = sum / n;
    double ss = 0;
    for (const Yuv& y : texels) ss += (y[c] - mean) * (y[c] - mean);
    out[2 * c] = mean;
    out[2 * c + 1] = texels.size() == 1 ? 0.0 : ss / (n - 1);
  }
  return static_cast<int>(texels.size());
}

// The patch's texel statistics: each face's, weighted by its share of the texels.
TexelStats texel_stats(const Patch& p, const GpTexture& tex, int& total) {
  std::vector<std::array<double, 6>> face(p.f.size());
  std::vector<int> count(p.f.size());
  total = 0;
  for (std::size_t f = 0; f < p.f.size(); ++f) {
    count[f] = face_texels(p.face_uv[f], tex, face[f]);
    total += count[f];
  }
  std::array<double, 6> s{};
  for (std::size_t f = 0; f < p.f.size(); ++f) {
    const double w = static_cast<double>(count[f]) / total;
    for (int k = 0; k < 6; ++k) s[k] += w * face[f][k];
  }
  return {s[0], s[1], s[2], s[3], s[4], s[5]};
}

// The centre's row of the cotangent Laplacian (gptoolbox's cotmatrix, entries added in its
// order: the nine entry kinds, each over every face).
std::vector<double> cotangent_row(const Patch& p) {
  const std::size_t nf = p.f.size();
  std::vector<std::array<double, 3>> cot(nf);  // cot12, cot23, cot31
  for (std::size_t f = 0; f < nf; ++f) {
    const P3 &a = p.v[p.f[f][0]], &b = p.v[p.f[f][1]], &c = p.v[p.f[f][2]];
    const P3 v1 = sub(c, b), v2 = sub(a, c), v3 = sub(b, a);
    const double dbl_a = norm(cross(v1, v2));
    auto dot = [](const P3& x, const P3& y) { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; };
    cot[f] = {-dot(v1, v2) / (dbl_a * 2), -dot(v2, v3) / (dbl_a * 2), -dot(v3, v1) / (dbl_a * 2)};
  }
  // Entry kinds: (row corner, column corner, value) with diag_i = -cot_a - cot_b.
  std::vector<double> row(p.v.size(), 0.0);
  const int kinds[9][2] = {{0, 1}, {1, 0}, {1, 2}, {2, 1}, {2, 0}, {0, 2}, {0, 0}, {1, 1}, {2, 2}};
  for (int k = 0; k < 9; ++k) {
    for (std::size_t f = 0; f < nf; ++f) {
      if (p.f[f][kinds[k][0]] != p.centre) continue;
      const auto& c = cot[f];
      const double value[9] = {c[0], c[0],         c[1],         c[1],        c[2],
                               c[2], -c[0] - c[2], -c[0] - c[1], -c[2] - c[1]};
      row[p.f[f][kinds[k][1]]] += value[k];
    }
  }
  return row;
}

// The centre's Voronoi-mixed mass (gptoolbox's massmatrix_intrinsic, intrinsic edge lengths).
double centre_mass(const Patch& p) {
  const std::size_t nf = p.f.size();
  std::vector<std::array<double, 3>> quads(nf);
  for (std::size_t f = 0; f < nf; ++f) {
    const P3 &p1 = p.v[p.f[f][0]], &p2 = p.v[p.f[f][1]], &p3 = p.v[p.f[f][2]];
    const double l1 = length(p2, p3), l2 = length(p1, p3), l3 = length(p1, p2);
    const double cos[3] = {(l3 * l3 + l2 * l2 - l1 * l1) / (2 * l2 * l3),
                           (l1 * l1 + l3 * l3 - l2 * l2) / (2 * l1 * l3),
                           (l1 * l1 + l2 * l2 - l3 * l3) / (2 * l1 * l2)};
    const double bary[3] = {cos[0] * l1, cos[1] * l2, cos[2] * l3};
    const double bsum = bary[0] + bary[1] + bary[2];
    const double area =
        0.25 * std::sqrt((l1 + l2 - l3) * (l1 - l2 + l3) * (-l1 + l2 + l3) * (l1 + l2 + l3));
    double part[3];
    for (int k = 0; k < 3; ++k) part[k] = area * (bary[k] / bsum);
    auto& q = quads[f];
    q = {(part[1] + part[2]) * 0.5, (part[0] + part[2]) * 0.5, (part[0] + part[1]) * 0.5};
    if (cos[0] < 0) q = {area * 0.5, area * 0.25, area * 0.25};
    if (cos[1] < 0) q = {area * 0.25, area * 0.5, area * 0.25};
    if (cos[2] < 0) q = {area * 0.25, area * 0.25, area * 0.5};
  }
  double m = 0;
  for (int k = 0; k < 3; ++k) {
    for (std::size_t f = 0; f < nf; ++f) {
      if (p.f[f][k] == p.centre) m += quads[f][k];
    }
  }
  return m;
}

// Discrete mean curvature at the centre: (1 / (2 M_cc)) sum_j L_cj (p_c - p_j) . n, n the
// area-weighted (before shrinking) sum of the shrunk faces' unit normals.
double mean_curvature(const Patch& p, const std::vector<double>& weights) {
  P3 normal{0, 0, 0};
  for (std::size_t f = 0; f < p.f.size(); ++f) {
    const P3& a = p.v[p.f[f][0]];
    P3 n = cross(sub(p.v[p.f[f][1]], a), sub(p.v[p.f[f][2]], a));
    const double z = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (z > 0) {
      const double len = std::sqrt(z);
      for (double& x : n) x /= len;
    }
    for (int d = 0; d < 3; ++d) normal[d] += weights[f] * n[d];
  }
  const std::vector<double> row = cotangent_row(p);
  const double k = 1 / (2 * centre_mass(p));
  P3 cur{0, 0, 0};
  const P3& c = p.v[p.centre];
  for (std::size_t j = 0; j < p.v.size(); ++j) {
    const double s = k * row[j];
    for (int d = 0; d < 3; ++d) cur[d] += s * (c[d] - p.v[j][d]);
  }
  return cur[0] * normal[0] + cur[1] * normal[1] + cur[2] * normal[2];
}

}  // namespace

KeypointValues keypoint_values(const PatchSource& ref_src, const PatchSource& dis_src,
                               const P3& keypoint, double threshold) {
  KeypointValues out;
  Patch ref = make_patch(ref_src, keypoint), dis = make_patch(dis_src, keypoint);
  // The reference skips patches of three vertices or fewer.
  constexpr std::size_t kMinPatchVertices = 4;
  if (ref.v.size() < kMinPatchVertices || dis.v.size() < kMinPatchVertices) return out;
  out.center_shift = std::fabs(ref.shift - dis.shift);
  const std::vector<double> ref_w = area_weights(ref), dis_w = area_weights(dis);
  out.patch_size = crop(ref, dis, *ref_src.texture, *dis_src.texture, threshold);
  // Flag: the centres' shift within one patch size -> 1, two -> 2, else 3.
  out.flag = out.center_shift <= out.patch_size       ? 1
             : out.center_shift <= 2 * out.patch_size ? 2
                                                      : 3;
  out.ref_smooth = colour_smoothness(ref);
  out.dis_smooth = colour_smoothness(dis);
  out.ref_stats = texel_stats(ref, *ref_src.texture, out.ref_npix);
  out.dis_stats = texel_stats(dis, *dis_src.texture, out.dis_npix);
  out.ref_cur = mean_curvature(ref, ref_w);
  out.dis_cur = mean_curvature(dis, dis_w);
  return out;
}

}  // namespace qm3d::mesh::gpsim
