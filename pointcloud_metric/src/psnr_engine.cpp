#include "psnr_engine.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>
#include <nanoflann.hpp>
#include <numeric>

namespace qm3d::pointcloud::detail {

// ---- loading (P: PccPointCloud::load) -------------------------------------------------------

namespace {

std::uint8_t to_byte(double c) {  // our readers give c = u / 255 for 8-bit colours: u back
  const double v = std::round(std::clamp(c, 0.0, 1.0) * 255.0);
  return static_cast<std::uint8_t>(v);
}

Point3f to_float(const Vec3& v) {
  return {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
}

// A float's bits mapped so that their unsigned order is the float order, -0 and +0 as one key
// (they compare equal). Coordinates are finite here (the readers refuse NaN and infinities).
std::uint64_t sort_key(float f) {
  if (f == 0.0f) f = 0.0f;
  std::uint32_t u = 0;
  std::memcpy(&u, &f, sizeof u);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

// The order of the sort after loading: std::array<float, 3>'s lexicographic operator<, ties
// (equal positions) by file order, as pc_error's comparator (std::sort of the points with a
// comparator that breaks ties by index: a total order, so any correct sort gives this
// permutation). Computed by a least-significant-digit radix sort: stable counting sorts on z,
// then y, then x, 11 bits at a time, each over (key, index) pairs; a digit all points share is
// skipped.
std::vector<std::uint32_t> sorted_order(const std::vector<Point3f>& p) {
  const std::size_t n = p.size();
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::vector<std::uint64_t> items(n), scratch(n);
  constexpr int kBits = 11;
  std::vector<std::size_t> count(std::size_t(1) << kBits);
  for (int dim = 2; dim >= 0; --dim) {
    for (std::size_t k = 0; k < n; ++k) items[k] = (sort_key(p[order[k]][dim]) << 32) | order[k];
    for (int shift = 32; shift < 64; shift += kBits) {
      const auto digit = [&](std::uint64_t v) { return (v >> shift) & ((1u << kBits) - 1); };
      std::fill(count.begin(), count.end(), 0);
      for (std::uint64_t v : items) ++count[digit(v)];
      if (n == 0 || count[digit(items[0])] == n) continue;
      std::size_t start = 0;
      for (std::size_t& c : count) start += std::exchange(c, start);
      for (std::uint64_t v : items) scratch[count[digit(v)]++] = v;
      items.swap(scratch);
    }
    for (std::size_t k = 0; k < n; ++k) order[k] = static_cast<std::uint32_t>(items[k]);
  }
  return order;
}

}  // namespace

MpegCloud load_mpeg_cloud(const std::vector<Vec3>& positions, const std::vector<Rgb>* colour_in,
                          const std::vector<Vec3>& normals, int duplicates, bool weighted,
                          bool average_normals) {
  const std::size_t n = positions.size();
  std::vector<Point3f> input(n);
  for (std::size_t i = 0; i < n; ++i) input[i] = to_float(positions[i]);
  const std::vector<std::uint32_t> order = sorted_order(input);
  const bool colours = colour_in != nullptr && !colour_in->empty();

  MpegCloud out;
  out.of_input.resize(n);
  out.points.reserve(n);
  if (colours) out.colours.reserve(n);
  if (!normals.empty()) out.normals.reserve(n);
  out.merged.reserve(n);
  for (std::size_t first = 0; first < n;) {
    std::size_t last = first + 1;  // the run of positions equal to order[first]'s
    while (last < n && input[order[last]] == input[order[first]]) ++last;
    const std::size_t run = last - first;
    // Kept: every point (dropdups 0), else the first of the run (std::unique), which holds the
    // run's truncated mean colour (long sums / count) when averaging.
    const std::size_t kept_end = duplicates == 0 ? last : first + 1;
    const std::size_t base = out.points.size();
    for (std::size_t k = first; k < kept_end; ++k) {
      const std::uint32_t i = order[k];
      out.points.push_back(input[i]);
      if (!normals.empty()) {
        Point3f n = to_float(normals[i]);
        if (average_normals && duplicates == 2 && run > 1) {
          Point3f sum{0, 0, 0};
          for (std::size_t m = first; m < last; ++m) {
            const Point3f o = to_float(normals[order[m]]);
            for (int c = 0; c < 3; ++c) sum[c] += o[c];
          }
          for (int c = 0; c < 3; ++c) n[c] = sum[c] / static_cast<float>(run);
        }
        out.normals.push_back(n);
      }
      out.merged.push_back(duplicates == 2 && weighted ? static_cast<int>(run) : 1);
      if (!colours) continue;
      const Rgb& own = (*colour_in)[i];
      Colour8 c{to_byte(own.r), to_byte(own.g), to_byte(own.b)};
      if (duplicates == 2 && run > 1) {
        long sum[3] = {0, 0, 0};
        for (std::size_t m = first; m < last; ++m) {
          const Rgb& rgb = (*colour_in)[order[m]];
          sum[0] += to_byte(rgb.r);
          sum[1] += to_byte(rgb.g);
          sum[2] += to_byte(rgb.b);
        }
        for (int ch = 0; ch < 3; ++ch) c[ch] = static_cast<std::uint8_t>(sum[ch] / long(run));
      }
      out.colours.push_back(c);
    }
    for (std::size_t k = first; k < last; ++k) {
      out.of_input[order[k]] = static_cast<std::uint32_t>(duplicates == 0 ? base + (k - first) : base);
    }
    if (duplicates != 0) out.duplicates += run - 1;
    first = last;
  }
  return out;
}

// ---- the tree --------------------------------------------------------------------------------

namespace {

struct PointsAdaptor {
  const std::vector<Point3f>& points;
  std::size_t kdtree_get_point_count() const { return points.size(); }
  float kdtree_get_pt(std::size_t i, std::size_t dim) const { return points[i][dim]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

// pc_error's my_kd_tree_t: metric_L2_double = L2_Adaptor<float, ..., double>, uint32 indices.
using Nanoflann =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Adaptor<float, PointsAdaptor, double>,
                                        PointsAdaptor, 3, std::uint32_t>;

}  // namespace

struct MpegTree::Impl {
  explicit Impl(const std::vector<Point3f>& p)
      : adaptor{p}, tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(10)) {}
  PointsAdaptor adaptor;
  Nanoflann tree;
};

MpegTree::MpegTree(const std::vector<Point3f>& points) : impl_(std::make_unique<Impl>(points)) {}
MpegTree::~MpegTree() = default;

std::size_t MpegTree::knn(const Point3f& query, std::size_t k, std::uint32_t* indices,
                          double* distances2) const {
  k = std::min(k, impl_->adaptor.points.size());
  if (k == 0) return 0;
  nanoflann::KNNResultSet<double, std::uint32_t, std::size_t> set(k);
  set.init(indices, distances2);
  impl_->tree.findNeighbors(set, query.data(), nanoflann::SearchParams());
  return set.size();
}

std::size_t MpegTree::expanding_knn(const Point3f& query, std::size_t first, bool expand,
                                    std::uint32_t* indices, double* distances2) const {
  std::size_t k = first;
  std::size_t found = knn(query, k, indices, distances2);
  // A cloud with fewer points than k has all of them in the result: nothing to expand (pc_error
  // then reads results that were never written).
  while (expand && found == k && distances2[0] == distances2[k - 1] && k + 5 <= kMaxNeighbours) {
    k += 5;
    found = knn(query, k, indices, distances2);
  }
  return found;
}

}  // namespace qm3d::pointcloud::detail
