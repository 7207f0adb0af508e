// GeodesicPSIM's meshes: the OBJ and texture as its reference reads them, its cleaning and its
// subdivision (SPEC-GEODESICPSIM steps 1, 2 and 4). Reference: Qi-Yangsjtu/GeodesicPSIM @ 3e06453.
#include <stb/stb_image.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <unordered_map>

#include "geodesicpsim_internal.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"

namespace qm3d::mesh::gpsim {
namespace {

[[noreturn]] void fail(const std::string& name, const std::string& what) {
  throw FormatError(name + ": " + what);
}

bool is_space(char c) { return c == ' ' || (c >= '\t' && c <= '\r'); }

// Splits one line into whitespace-separated words (as std::istringstream >> word does).
void words_of(const char* begin, const char* end,
              std::vector<std::pair<const char*, const char*>>& out) {
  out.clear();
  const char* p = begin;
  while (p < end) {
    while (p < end && is_space(*p)) ++p;
    const char* w = p;
    while (p < end && !is_space(*p)) ++p;
    if (p > w) out.emplace_back(w, p);
  }
}

// The reference parses every number with std::stof: float32 (strtof), then widens it to double.
// A word strtof cannot start reading, or out of float range, is an error (stof throws there).
double stof_widened(const char* w, const char* end, const std::string& name, std::size_t line) {
  const std::string word(w, end);
  char* stop = nullptr;
  errno = 0;
  const float x = std::strtof(word.c_str(), &stop);
  if (stop == word.c_str() || errno == ERANGE || !std::isfinite(x)) {
    fail(name, "line " + std::to_string(line) + ": '" + word + "' is not a finite float32 number");
  }
  return static_cast<double>(x);
}

// The vertex and UV index of a face corner "a/t" or "a/t/n" (1-based, as std::stoi reads them).
std::array<long long, 2> corner_indices(const char* w, const char* end, const std::string& name,
                                        std::size_t line) {
  const std::string word(w, end);
  const auto slash = word.find('/');
  std::array<long long, 2> out{0, 0};
  const std::string parts[2] = {word.substr(0, slash),
                                slash == std::string::npos ? "" : word.substr(slash + 1)};
  for (int k = 0; k < 2; ++k) {
    char* stop = nullptr;
    errno = 0;
    out[k] = std::strtoll(parts[k].c_str(), &stop, 10);
    if (stop == parts[k].c_str() || errno == ERANGE || out[k] < 1) {
      fail(name, "line " + std::to_string(line) + ": face corner '" + word +
                     "' is not v/vt or v/vt/vn with positive indices (geodesicpsim needs a "
                     "texture coordinate on every corner)");
    }
  }
  return out;
}

struct ObjLines {
  GpMesh mesh;
  std::vector<std::array<long long, 6>> faces;  // v, vt of each corner, 1-based
};

void read_line(const char* b, const char* e, std::size_t line, const std::string& name,
               std::vector<std::pair<const char*, const char*>>& words, ObjLines& out) {
  const std::size_t n = static_cast<std::size_t>(e - b);
  // The reference's line tests: "v ", "vt ", "f " at the start of the line.
  if (n >= 2 && b[0] == 'v' && b[1] == ' ') {
    words_of(b + 2, e, words);
    if (words.size() < 3) fail(name, "line " + std::to_string(line) + ": v needs x y z");
    P3 p;
    for (int k = 0; k < 3; ++k) p[k] = stof_widened(words[k].first, words[k].second, name, line);
    out.mesh.v.push_back(p);
  } else if (n >= 3 && b[0] == 'v' && b[1] == 't' && b[2] == ' ') {
    words_of(b + 2, e, words);
    if (words.size() < 2) fail(name, "line " + std::to_string(line) + ": vt needs u v");
    P2 t;
    for (int k = 0; k < 2; ++k) t[k] = stof_widened(words[k].first, words[k].second, name, line);
    out.mesh.uv.push_back(t);
  } else if (n >= 2 && b[0] == 'f' && b[1] == ' ') {
    words_of(b + 2, e, words);
    if (words.size() != 3) {
      fail(name, "line " + std::to_string(line) +
                     ": geodesicpsim reads triangles only (its reference keeps a polygon's first "
                     "three corners)");
    }
    std::array<long long, 6> f{};
    for (int k = 0; k < 3; ++k) {
      const auto c = corner_indices(words[k].first, words[k].second, name, line);
      f[2 * k] = c[0];
      f[2 * k + 1] = c[1];
    }
    out.faces.push_back(f);
  }
}

}  // namespace

GpMesh read_obj_as_reference(const std::string& text, const std::string& name) {
  ObjLines lines;
  std::vector<std::pair<const char*, const char*>> words;
  const char* p = text.data();
  const char* end = p + text.size();
  std::size_t line = 0;
  while (p < end) {
    const char* e = std::find(p, end, '\n');
    read_line(p, e, ++line, name, words, lines);
    p = e + (e < end ? 1 : 0);
  }
  GpMesh& m = lines.mesh;
  if (lines.faces.empty()) fail(name, "no faces (geodesicpsim needs a textured triangle mesh)");
  if (m.uv.empty()) fail(name, "no texture coordinates (vt): geodesicpsim needs a textured mesh");
  const auto nv = static_cast<long long>(m.v.size()), nt = static_cast<long long>(m.uv.size());
  for (const auto& f : lines.faces) {
    Tri a, t;
    for (int k = 0; k < 3; ++k) {
      if (f[2 * k] > nv || f[2 * k + 1] > nt) fail(name, "a face index is out of range");
      a[k] = static_cast<int>(f[2 * k] - 1);
      t[k] = static_cast<int>(f[2 * k + 1] - 1);
    }
    m.f.push_back(a);
    m.ft.push_back(t);
  }
  return m;
}

GpTexture read_texture_8bit(const std::filesystem::path& file) {
  const std::string bytes = read_file_bytes(file, kMaxTextureBytes);
  if (bytes.size() > static_cast<std::size_t>(INT_MAX)) fail(file.string(), "image too large");
  constexpr int kRgb = 3;  // OpenCV imread(path, IMREAD_COLOR) in the reference: 8-bit colour
  int w = 0, h = 0, channels = 0;
  const std::unique_ptr<unsigned char, void (*)(void*)> pixels(
      stbi_load_from_memory(reinterpret_cast<const unsigned char*>(bytes.data()),
                            static_cast<int>(bytes.size()), &w, &h, &channels, kRgb),
      stbi_image_free);
  if (!pixels) {
    fail(file.string(), std::string("cannot decode the texture image (") + stbi_failure_reason() +
                            "); PNG and JPEG are supported");
  }
  GpTexture t{w, h, {}};
  t.rgb.assign(pixels.get(), pixels.get() + static_cast<std::size_t>(w) * h * kRgb);
  return t;
}

// ---- Cleaning (SPEC step 2) ------------------------------------------------------------------

namespace {

// Equal values are one key: -0 and +0 too (the reference's hash maps them alike).
template <std::size_t N>
struct ArrayHash {
  std::size_t operator()(const std::array<double, N>& a) const {
    std::size_t h = 0;
    for (double x : a) h = h * 1000003u ^ std::hash<double>()(x == 0 ? 0.0 : x);
    return h;
  }
};

// Keeps the referenced entries of `values` in index order; renumbers `faces`.
template <typename T>
void drop_unreferenced(std::vector<T>& values, std::vector<Tri>& faces) {
  std::vector<int> map(values.size(), -1);
  for (const Tri& f : faces) {
    for (int i : f) map[static_cast<std::size_t>(i)] = 0;
  }
  std::vector<T> kept;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (map[i] == 0) {
      map[i] = static_cast<int>(kept.size());
      kept.push_back(values[i]);
    }
  }
  for (Tri& f : faces) {
    for (int& i : f) i = map[static_cast<std::size_t>(i)];
  }
  values = std::move(kept);
}

// Merges equal values (the first occurrence keeps its place); renumbers `faces`.
template <std::size_t N>
void merge_equal(std::vector<std::array<double, N>>& values, std::vector<Tri>& faces) {
  std::unordered_map<std::array<double, N>, int, ArrayHash<N>> first(values.size());
  std::vector<int> map(values.size());
  std::vector<std::array<double, N>> kept;
  for (std::size_t i = 0; i < values.size(); ++i) {
    const auto [it, added] = first.emplace(values[i], static_cast<int>(kept.size()));
    if (added) kept.push_back(values[i]);
    map[i] = it->second;
  }
  for (Tri& f : faces) {
    for (int& i : f) i = map[static_cast<std::size_t>(i)];
  }
  values = std::move(kept);
}

// |(v0 - v1) x (v2 - v1)|, the reference's face size (twice the area).
double face_size(const GpMesh& m, const Tri& f) {
  const P3 &p0 = m.v[f[0]], &p1 = m.v[f[1]], &p2 = m.v[f[2]];
  const double a[3] = {p0[0] - p1[0], p0[1] - p1[1], p0[2] - p1[2]};
  const double b[3] = {p2[0] - p1[0], p2[1] - p1[1], p2[2] - p1[2]};
  const double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                       a[0] * b[1] - a[1] * b[0]};
  return std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
}

struct TriHash {
  std::size_t operator()(const Tri& t) const {
    return (static_cast<std::size_t>(t[0]) * 73856093u) ^
           (static_cast<std::size_t>(t[1]) * 19349663u) ^
           (static_cast<std::size_t>(t[2]) * 83492791u);
  }
};

// Drops faces with a repeated vertex or a float32 size of 0, then repeated rows (same order).
void drop_bad_faces(GpMesh& m) {
  std::vector<Tri> f, ft;
  std::unordered_map<Tri, int, TriHash> seen(m.f.size());
  for (std::size_t i = 0; i < m.f.size(); ++i) {
    const Tri& t = m.f[i];
    if (t[0] == t[1] || t[0] == t[2] || t[1] == t[2]) continue;
    if (static_cast<float>(face_size(m, t)) == 0) continue;  // the reference's float test
    if (!seen.emplace(t, 0).second) continue;
    f.push_back(t);
    ft.push_back(m.ft[i]);
  }
  m.f = std::move(f);
  m.ft = std::move(ft);
}

}  // namespace

GpMesh clean_mesh(GpMesh m) {
  // A single wrap of each UV component into [0, 1]: > 1 minus 1, then < 0 plus 1.
  for (P2& t : m.uv) {
    for (double& x : t) {
      if (x > 1) x -= 1;
      if (x < 0) x += 1;
    }
  }
  drop_unreferenced(m.v, m.f);
  drop_unreferenced(m.uv, m.ft);
  merge_equal(m.v, m.f);
  merge_equal(m.uv, m.ft);
  drop_bad_faces(m);
  drop_unreferenced(m.v, m.f);
  drop_unreferenced(m.uv, m.ft);
  return m;
}

// ---- Subdivision (SPEC step 4) ---------------------------------------------------------------

namespace {

P3 mid(const P3& a, const P3& b) {
  return {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
}
P2 mid(const P2& a, const P2& b) { return {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2}; }

// Appends face i of `a` to `out` with its own three corners (positions and UVs), split into four
// at its edge midpoints when `split` (the reference's corner and face order).
void append_face(const GpMesh& a, std::size_t i, bool split, GpMesh& out) {
  const Tri &f = a.f[i], &t = a.ft[i];
  const int base = static_cast<int>(out.v.size());
  const P3 &p1 = a.v[f[0]], &p2 = a.v[f[1]], &p3 = a.v[f[2]];
  const P2 &u1 = a.uv[t[0]], &u2 = a.uv[t[1]], &u3 = a.uv[t[2]];
  out.v.insert(out.v.end(), {p1, p2, p3});
  out.uv.insert(out.uv.end(), {u1, u2, u3});
  if (!split) {
    out.f.push_back({base, base + 1, base + 2});
  } else {
    out.v.insert(out.v.end(), {mid(p1, p2), mid(p2, p3), mid(p3, p1)});
    out.uv.insert(out.uv.end(), {mid(u1, u2), mid(u2, u3), mid(u3, u1)});
    const int a12 = base + 3, a23 = base + 4, a31 = base + 5;
    out.f.insert(out.f.end(), {Tri{base, a12, a31}, Tri{a12, base + 1, a23}, Tri{a12, a23, a31},
                               Tri{a31, a23, base + 2}});
  }
  out.ft.resize(out.f.size());
  for (std::size_t k = out.ft.size() - (split ? 4 : 1); k < out.ft.size(); ++k)
    out.ft[k] = out.f[k];
}

GpMesh midpoint_subdivision(GpMesh m, int rounds) {
  for (int r = 0; r < rounds; ++r) {
    GpMesh out;
    for (std::size_t i = 0; i < m.f.size(); ++i) append_face(m, i, true, out);
    m = std::move(out);
  }
  return m;
}

// Splits the ceil((target - F) / 3) largest faces (every face at least as large as the sorted
// threshold, so ties all split).
GpMesh target_subdivision(const GpMesh& m, std::size_t target_faces) {
  const std::size_t count = m.f.size();
  const auto to_split =
      static_cast<std::size_t>(std::ceil((double(target_faces) - double(count)) / 3.0));
  std::vector<double> size(count);
  for (std::size_t i = 0; i < count; ++i) size[i] = face_size(m, m.f[i]);
  std::vector<double> sorted = size;
  std::sort(sorted.begin(), sorted.end());
  const double threshold = sorted[count - std::min(to_split, count)];
  GpMesh out;
  for (std::size_t i = 0; i < count; ++i) append_face(m, i, !(size[i] < threshold), out);
  return out;
}

// The reference's rule: n = the smallest integer with 4^n >= big / small (a float32 ratio);
// n - 1 rounds of midpoint subdivision, then the target split when still short of faces.
GpMesh subdivide_toward(const GpMesh& small, std::size_t target_faces) {
  const float ratio = static_cast<float>(target_faces) / static_cast<float>(small.f.size());
  int n = 0;
  while (std::pow(4.0, n) < ratio) ++n;
  const int rounds = n - 1;
  if (rounds < 1) return clean_mesh(target_subdivision(small, target_faces));
  GpMesh sub = clean_mesh(midpoint_subdivision(small, rounds));
  if (target_faces > sub.f.size()) return clean_mesh(target_subdivision(sub, target_faces));
  return sub;
}

}  // namespace

Subdivided equalise_face_counts(GpMesh& reference, GpMesh& distorted) {
  if (distorted.f.size() > reference.f.size()) {
    reference = subdivide_toward(reference, distorted.f.size());
    return Subdivided::kReference;
  }
  if (distorted.f.size() < reference.f.size()) {
    distorted = subdivide_toward(distorted, reference.f.size());
    return Subdivided::kDistorted;
  }
  return Subdivided::kNone;
}

// ---- Keypoints and nearest vertices (SPEC steps 5, 6) ----------------------------------------

namespace {

// The reference's Euclidean distance: sqrt((dx² + dy²) + dz²).
double distance(const P3& a, const P3& b) {
  const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

}  // namespace

// Below this many vertices the distance updates run on one thread: a parallel region per keypoint
// costs more than it saves (5000 regions of 20k distances: slower on 2 threads than on one).
constexpr std::ptrdiff_t kParallelFpsVertices = 1 << 18;

std::vector<P3> farthest_points(const std::vector<P3>& vertices, int count, int threads) {
  std::vector<P3> out;
  out.reserve(static_cast<std::size_t>(count));
  out.push_back(vertices[0]);  // the reference starts at vertex 0 (its random start is disabled)
  std::vector<double> d(vertices.size());
  const auto n = static_cast<std::ptrdiff_t>(vertices.size());
#pragma omp parallel for schedule(static) num_threads(threads) if (n >= kParallelFpsVertices)
  for (std::ptrdiff_t j = 0; j < n; ++j) d[j] = distance(vertices[j], out[0]);
  for (int i = 1; i < count; ++i) {
    // std::max_element: the first of equal maxima.
    const auto far = static_cast<std::size_t>(std::max_element(d.begin(), d.end()) - d.begin());
    out.push_back(vertices[far]);
    const P3 k = vertices[far];
#pragma omp parallel for schedule(static) num_threads(threads) if (n >= kParallelFpsVertices)
    for (std::ptrdiff_t j = 0; j < n; ++j) d[j] = std::min(distance(vertices[j], k), d[j]);
  }
  return out;
}

NearestVertex::NearestVertex(const std::vector<P3>& points) : points_(points) {
  order_.resize(points.size());
  for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = static_cast<int>(i);
  if (!order_.empty()) build(0, static_cast<int>(order_.size()));
}

int NearestVertex::build(int begin, int end) {
  constexpr int kLeafSize = 8;
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back(Node{begin, end});
  if (end - begin <= kLeafSize) return id;
  P3 lo = points_[order_[begin]], hi = lo;
  for (int i = begin; i < end; ++i) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], points_[order_[i]][k]);
      hi[k] = std::max(hi[k], points_[order_[i]][k]);
    }
  }
  int axis = 0;
  for (int k = 1; k < 3; ++k) {
    if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
  }
  const int m = (begin + end) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + m, order_.begin() + end,
                   [&](int a, int b) { return points_[a][axis] < points_[b][axis]; });
  const double split = points_[order_[m]][axis];
  const int left = build(begin, m);
  const int right = build(m, end);
  nodes_[id].axis = axis;
  nodes_[id].split = split;
  nodes_[id].left = left;
  nodes_[id].right = right;
  return id;
}

void NearestVertex::search(int id, const P3& q, double& best_d, int& best_i) const {
  const Node& n = nodes_[id];
  if (n.axis < 0) {
    for (int k = n.begin; k < n.end; ++k) {
      const int i = order_[k];
      const double d = distance(points_[i], q);
      if (d < best_d || (d == best_d && i < best_i)) {
        best_d = d;
        best_i = i;
      }
    }
    return;
  }
  const double diff = q[n.axis] - n.split;
  const int near = diff < 0 ? n.left : n.right, far = diff < 0 ? n.right : n.left;
  search(near, q, best_d, best_i);
  // Conservative pruning: a point beyond the plane is at least |diff| away; the slack keeps
  // every point whose rounded distance could tie the best.
  constexpr double kSlack = 1 + 1e-12;
  if (std::fabs(diff) <= best_d * kSlack) search(far, q, best_d, best_i);
}

int NearestVertex::nearest(const P3& q, double& d) const {
  d = INFINITY;
  int best = INT_MAX;
  search(0, q, d, best);
  return best;
}

}  // namespace qm3d::mesh::gpsim
