#include "closest_point.h"

#include <omp.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "vec3_ops.h"

namespace qm3d::mesh::detail {
namespace {

/// Node ranges of more faces (points) are built as OpenMP tasks.
constexpr std::uint32_t kTaskFaces = 1u << 14;
/// Points per leaf of NearestPointIndex at most (16: about 6 % fewer search samples than 8 on
/// blob7; the answers do not depend on it).
constexpr std::uint32_t kLeafPoints = 16;

/// Nodes of NearestPointIndex's tree over `count` points.
std::size_t index_nodes(std::uint32_t count) {
  if (count <= kLeafPoints) return 1;
  return 1 + index_nodes(count / 2) + index_nodes(count - count / 2);
}

bool same_point(const Vec3& a, const Vec3& b) {
  return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/// CGAL's Construct_projected_point_3(Line_3(p1, p2), q) (Cartesian/function_objects.h).
Vec3 project_on_line(const Vec3& p1, const Vec3& p2, const Vec3& q) {
  const Vec3 d = sub(p2, p1);
  const Vec3 dp = sub(q, p1);
  const double lambda = (d[0] * dp[0] + d[1] * dp[1] + d[2] * dp[2]) /
                        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  return {p1[0] + lambda * d[0], p1[1] + lambda * d[1], p1[2] + lambda * d[2]};
}

/// CGAL's Construct_projected_point_3(Segment_3(s, t), q) (Kernel/function_objects.h).
Vec3 project_on_segment(const Vec3& s, const Vec3& t, const Vec3& q) {
  if (same_point(s, t)) return s;
  const Vec3 v = sub(t, s);
  if (dot(v, sub(q, s)) <= 0) return s;
  if (dot(v, sub(q, t)) >= 0) return t;
  return project_on_line(s, t, q);
}

/// CGAL's is_inside_triangle_3_aux: whether q (on the plane of normal w) lies beyond edge
/// p1 p2 within the edge's span, where `result` becomes its projection on the edge's line.
__attribute__((always_inline)) inline bool beyond_edge(const Vec3& w, const Vec3& p1,
                                                       const Vec3& p2, const Vec3& q, Vec3& result,
                                                       bool& outside) {
  const Vec3 v = cross(sub(p2, p1), sub(q, p1));
  if (dot(v, w) < 0) {
    if (dot(sub(q, p1), sub(p2, p1)) >= 0 && dot(sub(q, p2), sub(p1, p2)) >= 0) {
      result = project_on_line(p1, p2, q);
      return true;
    }
    outside = true;
  }
  return false;
}

/// CGAL's nearest_point_3: the corner nearest to q, the first on equal distances.
Vec3 nearest_corner(const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 da = sub(a, q), db = sub(b, q), dc = sub(c, q);
  const double d1 = dot(da, da), d2 = dot(db, db), d3 = dot(dc, dc);
  if (d2 >= d1 && d3 >= d1) return a;
  if (d3 >= d2) return b;
  return c;
}

/// Compute_squared_distance_3 and squared_distanceC3 (the same bits: (a - b)^2 = (b - a)^2).
double squared_distance(const Vec3& a, const Vec3& b) {
  const Vec3 d = sub(b, a);
  return dot(d, d);
}

// project_on_triangle, inlined into the closest-point search.
__attribute__((always_inline)) inline Vec3 projection(const Vec3& a, const Vec3& b, const Vec3& c,
                                                      const Vec3& q) {
  // Supporting plane (plane_from_pointsC3 with p = a, q = b, r = c).
  const double rpx = a[0] - c[0], rpy = a[1] - c[1], rpz = a[2] - c[2];
  const double rqx = b[0] - c[0], rqy = b[1] - c[1], rqz = b[2] - c[2];
  const double pa = rpy * rqz - rqy * rpz;
  const double pb = rpz * rqx - rqz * rpx;
  const double pc = rpx * rqy - rqx * rpy;
  const double pd = -pa * c[0] - pb * c[1] - pc * c[2];
  if (pa == 0 && pb == 0 && pc == 0) {
    // Degenerate plane: the segment of largest (signed) L-infinity extent, as CGAL picks it.
    const Vec3 ab = sub(b, a), ac = sub(c, a), bc = sub(c, b);
    const double linf_ab = std::max(std::max(ab[0], ab[1]), ab[2]);
    const double linf_ac = std::max(std::max(ac[0], ac[1]), ac[2]);
    const double linf_bc = std::max(std::max(bc[0], bc[1]), bc[2]);
    if (linf_ab > linf_ac) {
      return linf_ab > linf_bc ? project_on_segment(a, b, q) : project_on_segment(b, c, q);
    }
    return linf_ac > linf_bc ? project_on_segment(a, c, q) : project_on_segment(b, c, q);
  }
  // q projected on the plane (projection_planeC3).
  const double num = pa * q[0] + pb * q[1] + pc * q[2] + pd;
  const double den = pa * pa + pb * pb + pc * pc;
  const double lambda = num / den;
  const Vec3 proj{q[0] - lambda * pa, q[1] - lambda * pb, q[2] - lambda * pc};
  const Vec3 w{pa, pb, pc};
  Vec3 moved{0, 0, 0};
  bool outside = false;
  if (beyond_edge(w, a, b, proj, moved, outside) || beyond_edge(w, b, c, proj, moved, outside) ||
      beyond_edge(w, c, a, proj, moved, outside)) {
    return moved;
  }
  return outside ? nearest_corner(proj, a, b, c) : proj;
}

}  // namespace

Vec3 project_on_triangle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& q) {
  return projection(a, b, c, q);
}

struct NearestPointIndex::Search {
  Vec3 q;
  std::uint32_t best = 0;  ///< tree position
  double best_d2 = std::numeric_limits<double>::infinity();
  bool tie = false;
};

NearestPointIndex::NearestPointIndex(const ArrayView<Vec3>& positions,
                                     const std::vector<std::uint32_t>& which,
                                     const std::vector<std::uint32_t>& ids, int threads) {
  if (which.empty() || ids.size() != positions.size() || which.size() >= 0xffffffffu) {
    throw std::logic_error("NearestPointIndex: bad point set");
  }
  const auto count = static_cast<std::uint32_t>(which.size());
  std::vector<std::uint32_t> order = which;  // sorted into tree order by the build
  splits_.resize(index_nodes(count));
#pragma omp parallel num_threads(threads)
#pragma omp single
  build(order, 0, 0, count, positions);
  points_.resize(count);
  ids_.resize(count);
  for (std::uint32_t i = 0; i < count; ++i) {
    points_[i] = positions[order[i]];
    ids_[i] = ids[order[i]];
  }
}

// Splits at the median along the dimension of largest extent.
void NearestPointIndex::build(std::vector<std::uint32_t>& order, std::size_t node,
                              std::uint32_t first, std::uint32_t count,
                              const ArrayView<Vec3>& points) {
  if (count <= kLeafPoints) return;
  Vec3 lo = points[order[first]], hi = lo;
  for (std::uint32_t i = first + 1; i < first + count; ++i) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], points[order[i]][k]);
      hi[k] = std::max(hi[k], points[order[i]][k]);
    }
  }
  int dim = 0;
  for (int k = 1; k < 3; ++k) {
    if (hi[k] - lo[k] > hi[dim] - lo[dim]) dim = k;
  }
  const std::uint32_t half = count / 2;
  const auto begin = order.begin() + first;
  std::nth_element(begin, begin + half, begin + count, [&](std::uint32_t a, std::uint32_t b) {
    return points[a][dim] < points[b][dim];
  });
  Split& split = splits_[node];
  split.dim = dim;
  split.value = points[order[first + half]][dim];
  split.right = static_cast<std::uint32_t>(node + index_nodes(half) + 1);
  if (count > kTaskFaces) {
#pragma omp task default(shared) firstprivate(node, first, half)
    build(order, node + 1, first, half, points);
#pragma omp task default(shared) firstprivate(first, half, count)
    build(order, split.right, first + half, count - half, points);
#pragma omp taskwait
  } else {
    build(order, node + 1, first, half, points);
    build(order, split.right, first + half, count - half, points);
  }
}

// The far side of a split is searched when it may hold a point at most as near as the best:
// its points are at least |q - value| away along the split's dimension, and the rounded
// distances keep that order.
void NearestPointIndex::search(std::size_t node, std::uint32_t first, std::uint32_t count,
                               Search& s) const {
  if (count <= kLeafPoints) {
    for (std::uint32_t i = first; i < first + count; ++i) {
      // Euclidean_distance::transformed_distance: (q - p)^2 summed over x, y, z.
      const double d2 = squared_distance(points_[i], s.q);
      if (d2 < s.best_d2) {
        s.best = i;
        s.best_d2 = d2;
        s.tie = false;
      } else if (d2 == s.best_d2) {
        s.tie = true;
      }
    }
    return;
  }
  const Split& split = splits_[node];
  const std::uint32_t half = count / 2;
  const double diff = s.q[split.dim] - split.value;
  if (diff < 0) {
    search(node + 1, first, half, s);
    if (diff * diff <= s.best_d2) search(split.right, first + half, count - half, s);
  } else {
    search(split.right, first + half, count - half, s);
    if (diff * diff <= s.best_d2) search(node + 1, first, half, s);
  }
}

NearestPointIndex::Nearest NearestPointIndex::nearest(const Vec3& q) const {
  Search s;
  s.q = q;
  search(0, 0, static_cast<std::uint32_t>(points_.size()), s);
  return {points_[s.best], ids_[s.best], s.tie};
}

struct FaceBoxTree::Search {
  Vec3 q;
  ClosestPoint best;
  double best_d2;  ///< squared distance from q to best.point, as CGAL recomputes it
};

FaceBoxTree::FaceBoxTree(const ArrayView<Vec3>& positions, const ArrayView<Triangle>& triangles,
                         int threads)
    : positions_(positions), triangles_(triangles) {
  if (triangles.size() == 0) throw std::logic_error("FaceBoxTree: a mesh without faces");
  if (triangles.size() >= 0xffffffffu) throw std::length_error("FaceBoxTree: too many faces");
  const auto count = static_cast<std::uint32_t>(triangles.size());
  faces_.resize(count);
  std::iota(faces_.begin(), faces_.end(), 0u);
  if (count < 2) return;
  boxes_.resize(count - 1);
#pragma omp parallel num_threads(threads)
#pragma omp single
  build(0, 0, count);
}

// Compute_bbox: the union of the faces' boxes (each its corners' min and max).
FaceBoxTree::Box FaceBoxTree::bounds(std::uint32_t first, std::uint32_t count) const {
  Box b{positions_[triangles_[faces_[first]][0]], positions_[triangles_[faces_[first]][0]]};
  for (std::uint32_t i = first; i < first + count; ++i) {
    for (std::uint32_t v : triangles_[faces_[i]]) {
      for (int k = 0; k < 3; ++k) {
        b.lo[k] = std::min(b.lo[k], positions_[v][k]);
        b.hi[k] = std::max(b.hi[k], positions_[v][k]);
      }
    }
  }
  return b;
}

// AABB_tree::expand: the node's box, the split of its faces (Split_primitives: nth_element at
// the middle, by the reference point's coordinate along the box's longest axis, the first of
// x, y, z on equal extents as longest_axis decides), then its two children: primitives for 2
// faces, a primitive and a node of 2 for 3, else nodes of count / 2 and the rest. Pre-order
// layout: the left child node follows its parent, the right one after the left's count / 2 - 1
// nodes.
void FaceBoxTree::build(std::size_t node, std::uint32_t first, std::uint32_t count) {
  const Box box = bounds(first, count);
  boxes_[node] = box;
  const double dx = box.hi[0] - box.lo[0];
  const double dy = box.hi[1] - box.lo[1];
  const double dz = box.hi[2] - box.lo[2];
  const int axis = dx >= dy ? (dx >= dz ? 0 : 2) : (dy >= dz ? 1 : 2);
  const auto begin = faces_.begin() + first;
  std::nth_element(begin, begin + count / 2, begin + count,
                   [this, axis](std::uint32_t f1, std::uint32_t f2) {
                     return positions_[triangles_[f1][0]][axis] <
                            positions_[triangles_[f2][0]][axis];
                   });
  if (count == 2) return;
  if (count == 3) {
    build(node + 1, first + 1, 2);
    return;
  }
  const std::uint32_t half = count / 2;
  if (count > kTaskFaces) {
#pragma omp task default(shared) firstprivate(node, first, half)
    build(node + 1, first, half);
#pragma omp task default(shared) firstprivate(node, first, half, count)
    build(node + half, first + half, count - half);
#pragma omp taskwait
  } else {
    build(node + 1, first, half);
    build(node + half, first + half, count - half);
  }
}

namespace {

// AABB_traits::Compare_distance(q, box, bound) == SMALLER: do_intersect(Sphere_3(q, sr), box),
// do_intersect_sphere_box_3's arithmetic.
bool reaches(const Vec3& lo, const Vec3& hi, const Vec3& q, double sr) {
  double distance = 0;
  for (int k = 0; k < 3; ++k) {
    double d;
    if (q[k] < lo[k]) {
      d = lo[k] - q[k];
    } else if (q[k] > hi[k]) {
      d = q[k] - hi[k];
    } else {
      continue;
    }
    d = d * d;
    if (k < 2 && d > sr) return false;
    distance = k == 0 ? d : distance + d;
  }
  return distance <= sr;
}

}  // namespace

// Projection_traits::intersection: the face's closest point replaces the current one when it is
// not farther (AABB_traits::Closest_point) and is another point.
inline void FaceBoxTree::visit_face(std::uint32_t face, Search& s) const {
  const Triangle& t = triangles_[face];
  const Vec3 point = projection(positions_[t[0]], positions_[t[1]], positions_[t[2]], s.q);
  const double d2 = squared_distance(s.q, point);
  if (d2 > s.best_d2) return;
  if (same_point(point, s.best.point)) return;
  s.best = {point, face};
  s.best_d2 = d2;
}

// AABB_node::traversal with Projection_traits: a child node is entered when its box reaches the
// sphere through the current closest point, tested when its turn comes.
void FaceBoxTree::traverse(std::size_t node, std::uint32_t first, std::uint32_t count,
                           Search& s) const {
  switch (count) {
    case 2:
      visit_face(faces_[first], s);
      visit_face(faces_[first + 1], s);
      return;
    case 3:
      visit_face(faces_[first], s);
      if (reaches(boxes_[node + 1].lo, boxes_[node + 1].hi, s.q, s.best_d2)) {
        traverse(node + 1, first + 1, 2, s);
      }
      return;
    default: {
      const std::uint32_t half = count / 2;
      const Box& left = boxes_[node + 1];
      const Box& right = boxes_[node + half];
      if (reaches(left.lo, left.hi, s.q, s.best_d2)) {
        traverse(node + 1, first, half, s);
        if (reaches(right.lo, right.hi, s.q, s.best_d2)) {
          traverse(node + half, first + half, count - half, s);
        }
      } else if (reaches(right.lo, right.hi, s.q, s.best_d2)) {
        traverse(node + half, first + half, count - half, s);
      }
    }
  }
}

ClosestPoint FaceBoxTree::closest(const Vec3& q, const ClosestPoint& hint) const {
  Search s{q, hint, squared_distance(q, hint.point)};
  if (faces_.size() == 1) {
    visit_face(faces_[0], s);
  } else {
    traverse(0, 0, static_cast<std::uint32_t>(faces_.size()), s);
  }
  return s.best;
}

}  // namespace qm3d::mesh::detail
