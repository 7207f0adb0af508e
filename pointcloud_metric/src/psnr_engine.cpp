#include "psnr_engine.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <nanoflann.hpp>
#include <numeric>
#include <utility>

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
std::uint32_t sort_key(float f) {
  if (f == 0.0f) f = 0.0f;
  std::uint32_t u = 0;
  std::memcpy(&u, &f, sizeof u);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

// A point and its place in the file, as the sort moves them (16 bytes: the sort streams through
// them instead of looking the coordinates up by index, which misses the cache at every step).
struct SortRecord {
  Point3f p;
  std::uint32_t index;
};

// The order of the sort after loading: std::array<float, 3>'s lexicographic operator<, ties
// (equal positions) by file order, as pc_error's comparator (std::sort of the points with a
// comparator that breaks ties by index: a total order, so any correct sort gives this
// permutation). Computed by a least-significant-digit radix sort of the records: stable counting
// sorts on z, then y, then x, 11 bits at a time; a digit all points share is skipped. Frees
// `positions`.
std::vector<SortRecord> sorted_records(std::vector<Point3f>& positions) {
  const std::size_t n = positions.size();
  std::vector<SortRecord> items(n);
  for (std::size_t i = 0; i < n; ++i) items[i] = {positions[i], static_cast<std::uint32_t>(i)};
  std::vector<Point3f>().swap(positions);
  std::vector<SortRecord> scratch(n);
  constexpr int kBits = 11;
  std::vector<std::size_t> count(std::size_t(1) << kBits);
  for (int dim = 2; dim >= 0; --dim) {
    for (int shift = 0; shift < 32; shift += kBits) {
      const auto digit = [&](const SortRecord& r) {
        return (sort_key(r.p[dim]) >> shift) & ((1u << kBits) - 1);
      };
      std::fill(count.begin(), count.end(), 0);
      for (const SortRecord& r : items) ++count[digit(r)];
      if (n == 0 || count[digit(items[0])] == n) continue;
      std::size_t start = 0;
      for (std::size_t& c : count) start += std::exchange(c, start);
      for (const SortRecord& r : items) scratch[count[digit(r)]++] = r;
      items.swap(scratch);
    }
  }
  return items;
}

// The run of records from `first` on at the position of records[first].
std::size_t run_end(const std::vector<SortRecord>& records, std::size_t first) {
  std::size_t last = first + 1;
  while (last < records.size() && records[last].p == records[first].p) ++last;
  return last;
}

// The colour a kept point of the run [first, last) holds: its own, or with duplicates 2 the
// run's truncated mean (long sums / count).
Colour8 run_colour(const std::vector<SortRecord>& r, std::size_t first, std::size_t last,
                   std::size_t kept, const std::vector<Colour8>& colours, int duplicates) {
  if (duplicates != 2 || last - first == 1) return colours[r[kept].index];
  long sum[3] = {0, 0, 0};
  for (std::size_t m = first; m < last; ++m) {
    for (int c = 0; c < 3; ++c) sum[c] += colours[r[m].index][c];
  }
  Colour8 out;
  for (int c = 0; c < 3; ++c) out[c] = static_cast<std::uint8_t>(sum[c] / long(last - first));
  return out;
}

// The normal a kept point of the run holds: its own, or with average_normals and duplicates 2
// the run's float sum (in sorted order) / count.
Point3f run_normal(const std::vector<SortRecord>& r, std::size_t first, std::size_t last,
                   std::size_t kept, const std::vector<Point3f>& normals, const LoadRules& rules) {
  const std::size_t run = last - first;
  if (!(rules.average_normals && rules.duplicates == 2 && run > 1)) return normals[r[kept].index];
  Point3f sum{0, 0, 0};
  for (std::size_t m = first; m < last; ++m) {
    for (int c = 0; c < 3; ++c) sum[c] += normals[r[m].index][c];
  }
  Point3f n;
  for (int c = 0; c < 3; ++c) n[c] = sum[c] / static_cast<float>(run);
  return n;
}

}  // namespace

MpegCloud load_mpeg_cloud(FloatCloud cloud, const LoadRules& rules) {
  const std::size_t n = cloud.positions.size();
  const std::vector<SortRecord> records = sorted_records(cloud.positions);
  const bool colours = !cloud.colours.empty();
  const bool normals = !cloud.normals.empty();
  MpegCloud out;
  out.points.reserve(n);
  if (colours) out.colours.reserve(n);
  if (normals) out.normals.reserve(n);
  if (rules.weighted) out.merged.reserve(n);
  if (rules.keep_of_input) out.of_input.resize(n);
  for (std::size_t first = 0; first < n;) {
    const std::size_t last = run_end(records, first);
    // Kept: every point (dropdups 0), else the first of the run (std::unique).
    const std::size_t kept_end = rules.duplicates == 0 ? last : first + 1;
    const std::size_t base = out.points.size();
    for (std::size_t k = first; k < kept_end; ++k) {
      out.points.push_back(records[k].p);
      if (normals) out.normals.push_back(run_normal(records, first, last, k, cloud.normals, rules));
      if (rules.weighted) {
        out.merged.push_back(rules.duplicates == 2 ? static_cast<int>(last - first) : 1);
      }
      if (colours) {
        out.colours.push_back(run_colour(records, first, last, k, cloud.colours, rules.duplicates));
      }
    }
    for (std::size_t k = first; rules.keep_of_input && k < last; ++k) {
      out.of_input[records[k].index] =
          static_cast<std::uint32_t>(rules.duplicates == 0 ? base + (k - first) : base);
    }
    if (rules.duplicates != 0) out.duplicates += last - first - 1;
    first = last;
  }
  return out;
}

FloatCloud float_cloud(const std::vector<Vec3>& positions, const std::vector<Rgb>* colours,
                       const std::vector<Vec3>& normals) {
  FloatCloud out;
  out.positions.resize(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) out.positions[i] = to_float(positions[i]);
  if (colours != nullptr) {
    out.colours.resize(colours->size());
    for (std::size_t i = 0; i < colours->size(); ++i) {
      const Rgb& c = (*colours)[i];
      out.colours[i] = {to_byte(c.r), to_byte(c.g), to_byte(c.b)};
    }
  }
  out.normals.resize(normals.size());
  for (std::size_t i = 0; i < normals.size(); ++i) out.normals[i] = to_float(normals[i]);
  return out;
}

MpegCloud load_mpeg_cloud(const std::vector<Vec3>& positions, const std::vector<Rgb>* colours,
                          const std::vector<Vec3>& normals, int duplicates, bool weighted,
                          bool average_normals) {
  LoadRules rules;
  rules.duplicates = duplicates;
  rules.weighted = weighted;
  rules.average_normals = average_normals;
  rules.keep_of_input = true;
  return load_mpeg_cloud(float_cloud(positions, colours, normals), rules);
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
