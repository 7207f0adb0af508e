// The computation of pc_error 0.14.2 (MPEGGroup/mpeg-pcc-dmetric bd6df59), rule by rule. Internal
// to psnr.cpp; every rule names where pc_error has it (D: source/pcc_distortion.cpp,
// P: source/pcc_processing.cpp).
//
// Why float and nanoflann: pc_error holds coordinates and normals as float32 and searches with
// nanoflann 1.2.3 (KDTreeVectorOfVectorsAdaptor, leaf size 10, uint32 indices, distances in
// double of float differences). Which neighbours tie at the nearest distance - and so the
// colour and the D2 of every point of a voxelised cloud - depends on that tree's traversal
// order and on those float distances. Debian's nanoflann 1.4.3 builds and searches the same
// tree as 1.2.3 (the split rule, the result sets and searchLevel are unchanged between them;
// shared/docs/NANOFLANN-1.1.7.md §2), so it is used here with pc_error's element and distance
// types.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "qm3d/common/types.h"

namespace qm3d::pointcloud::detail {

using Point3f = std::array<float, 3>;
using Colour8 = std::array<std::uint8_t, 3>;

/// A cloud as read, at the precision pc_error reads it: float32 positions and normals, 8-bit
/// colours (psnr's own PLY reader gives these directly; other inputs are rounded to them).
struct FloatCloud {
  std::vector<Point3f> positions;
  std::vector<Colour8> colours;  ///< empty: none
  std::vector<Point3f> normals;  ///< empty: none
};

/// A cloud as pc_error holds it after loading (P: PccPointCloud::load): float32 positions sorted
/// lexicographically (ties by file order), duplicates handled, 8-bit colours, float32 normals.
struct MpegCloud {
  std::vector<Point3f> points;
  std::vector<Colour8> colours;  ///< empty: none
  std::vector<Point3f> normals;  ///< empty: none
  std::vector<int> merged;       ///< points a kept point stands for (nbdup; 1 unless averaged
                                 ///< with neighborsProc 2); empty unless LoadRules::weighted
  std::vector<std::uint32_t> of_input;  ///< input point -> the point here that holds it (empty
                                        ///< unless LoadRules::keep_of_input)
  std::size_t duplicates = 0;  ///< points removed (pc_error's "N points with same coordinates")

  std::size_t size() const { return points.size(); }
};

/// How a cloud is loaded: pc_error's --dropdups (`duplicates` 2: colour = truncated mean,
/// `merged` = run length when `weighted` (neighborsProc 2); 1: the first of each run kept; 0:
/// every point kept). A merged run keeps its first normal (pc_error), or with
/// `average_normals` their float sum (in sorted order) / count, unnormalised (mmetric's
/// removeDuplicatePoints). `keep_of_input`: fill MpegCloud::of_input (per-point maps).
struct LoadRules {
  int duplicates = 2;
  bool weighted = false;
  bool average_normals = false;
  bool keep_of_input = true;
};

/// Loads a cloud the way pc_error does: sorted, duplicates as `rules` say. Takes the cloud (its
/// arrays are freed as they are used: the sort holds 2 x 16 bytes per point).
MpegCloud load_mpeg_cloud(FloatCloud cloud, const LoadRules& rules);

/// A cloud at double precision rounded as pc_error reads it: positions and normals to float32,
/// colours 0..1 -> 0..255 (`colours` nullptr or empty: none).
FloatCloud float_cloud(const std::vector<Vec3>& positions, const std::vector<Rgb>* colours,
                       const std::vector<Vec3>& normals);

/// load_mpeg_cloud(float_cloud(...)) with `merged` and `of_input` filled.
MpegCloud load_mpeg_cloud(const std::vector<Vec3>& positions, const std::vector<Rgb>* colours,
                          const std::vector<Vec3>& normals, int duplicates, bool weighted,
                          bool average_normals = false);

/// pc_error's k-d tree over a cloud's points (nanoflann, float elements, double distances).
class MpegTree {
 public:
  explicit MpegTree(const std::vector<Point3f>& points);
  ~MpegTree();
  MpegTree(const MpegTree&) = delete;
  MpegTree& operator=(const MpegTree&) = delete;

  /// The min(k, size) nearest points to `query` in nanoflann's order (distance, then traversal);
  /// returns how many were written.
  std::size_t knn(const Point3f& query, std::size_t k, std::uint32_t* indices,
                  double* distances2) const;

  /// The neighbours pc_error's expanding query would return that matter when only the run of
  /// neighbours tied with the first counts (by `tied(d2_prev, d2_next)`): a 2-NN query first,
  /// which is the prefix of any larger query of the same tree (nanoflann's results are the first
  /// k of its (distance, traversal) order); when the first two are not tied, that first one
  /// alone, else expanding_knn(query, first, expand, ...). Returns the count written.
  template <typename Tied>
  std::size_t tie_run_knn(const Point3f& query, std::size_t first, bool expand, Tied tied,
                          std::uint32_t* indices, double* distances2) const {
    const std::size_t found = knn(query, 2, indices, distances2);
    if (found < 2 || !tied(distances2[0], distances2[1])) return std::min<std::size_t>(found, 1);
    return expanding_knn(query, first, expand, indices, distances2);
  }

  /// pc_error's expanding query (D: findMetric / scaleNormals): k = first, then k + 5, ...
  /// while `expand` and the first and the last of the k results are at the same distance and
  /// k + 5 <= 30. Returns the count found.
  std::size_t expanding_knn(const Point3f& query, std::size_t first, bool expand,
                            std::uint32_t* indices, double* distances2) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// At most this many neighbours are searched (D: num_results_max).
constexpr std::size_t kMaxNeighbours = 30;

}  // namespace qm3d::pointcloud::detail
