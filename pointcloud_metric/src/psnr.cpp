// pc_error's D1/D2/colour values (qm3d/pointcloud/psnr.h). The rules, each where pc_error 0.14.2
// has it (MPEGGroup/mpeg-pcc-dmetric bd6df59; D: source/pcc_distortion.cpp, P:
// source/pcc_processing.cpp):
// - Loading (P: load): float32 coordinates and normals, 8-bit colours, sorted, duplicates
//   averaged / dropped / kept (psnr_engine.cpp).
// - Peak (D: computeQualityMetric, findNNdistances): -r as float32; else the largest distance of
//   a point to its nearest other point of A (3-NN; a point whose first neighbour is not itself, or
//   whose second is within 1e-5, is skipped).
// - B's normals (D: scaleNormals, averageNormals = 1): every point of A adds its normal (float
//   sums, in A's order) to each point of B at exactly its nearest distance (the first 5, 10, ...
//   up to 30 neighbours searched while the first and the last tie); a point of B that received
//   nothing takes the mean of A's normals at exactly its nearest distance; then each sum is
//   divided by its count. averageNormals = 0: nearest point only. The pass B -> A uses A's own.
// - Per point of A (D: findMetric): its 10 nearest in B (15, ... 30 while the first and the last
//   tie, with averageNormals); the "same distance" set: the first, then each next one whose
//   squared distance is within 1e-8 of the previous one's (absolute, chained). D1 = squared
//   distance to the first (double differences of the floats). D2 (averageNormals) = mean over
//   the set of ((a - b) . n_b)^2 in float arithmetic (powf); else (e . n_first)^2 in double.
//   Colour (neighborsProc 1, 2) = the set's mean colour (weighted by merged duplicates for 2),
//   rounded; the per-channel error (in - out)^2 in float in the colour space, and in RGB for the
//   colour Hausdorff.
// - MSE = sum / #A; Hausdorff = max (starting at DBL_MIN); PSNR 10 log10(f p^2 / x), f = 3 for
//   geometry; symmetric = worse of the two directions per value.
// What qm3d does differently, documented in the README: the sums run in point order in fixed
// chunks (pc_error adds in thread order: same to ~1e-15 relative, and the same bits here for any
// thread count); a zero Hausdorff is reported as 0 with an infinite PSNR (pc_error prints
// DBL_MIN and 10 log10(3 p^2 / DBL_MIN)); NaN normals are refused (pc_error adds an unsquared
// sum of differences for them); clouds of fewer than 10 points use what they have.
#include "qm3d/pointcloud/psnr.h"

#include <omp.h>

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <future>
#include <memory>
#include <sstream>

#include "pca_normals.h"
#include "psnr_engine.h"
#include "psnr_reader.h"
#include "psnr_search.h"
#include "qm3d/common/error.h"
#include "qm3d/common/metric.h"
#include "qm3d/common/result_io.h"
#include "qm3d/common/version.h"
#include "qm3d/pointcloud/cloud_io.h"
#include "qm3d/pointcloud/metrics.h"

namespace qm3d::pointcloud {

using detail::Colour8;
using detail::kMaxNeighbours;
using detail::MpegCloud;
using detail::Point3f;
using detail::PsnrSearch;

const std::vector<std::string>& psnr_value_names() {
  static const std::vector<std::string> names = {"d1_mse",
                                                 "d1_psnr",
                                                 "d2_mse",
                                                 "d2_psnr",
                                                 "d1_hausdorff",
                                                 "d1_hausdorff_psnr",
                                                 "d2_hausdorff",
                                                 "d2_hausdorff_psnr",
                                                 "c0_mse",
                                                 "c1_mse",
                                                 "c2_mse",
                                                 "c0_psnr",
                                                 "c1_psnr",
                                                 "c2_psnr",
                                                 "c0_hausdorff",
                                                 "c1_hausdorff",
                                                 "c2_hausdorff",
                                                 "c0_hausdorff_psnr",
                                                 "c1_hausdorff_psnr",
                                                 "c2_hausdorff_psnr"};
  return names;
}

namespace {

/// Points per chunk of the sums (fixed: the sums do not depend on the thread count).
constexpr std::size_t kChunk = 4096;

int thread_count(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

/// D: getPSNR.
double psnr_of(double dist2, double peak, double factor = 1.0) {
  const double max_energy = peak * peak;
  return 10 * std::log10((factor * max_energy) / dist2);
}

/// D: convertRGBtoYUV.
std::array<float, 3> convert(PsnrColourSpace space, const Colour8& rgb) {
  switch (space) {
    case PsnrColourSpace::kRgb:
      return {float(rgb[0]), float(rgb[1]), float(rgb[2])};
    case PsnrColourSpace::kYCoCg: {
      const int r = rgb[0], g = rgb[1], b = rgb[2];
      const int co = r - b;
      const int t = b + (co >> 1);
      const int cg = g - t;
      const int y = t + (cg >> 1);
      constexpr int kOffset = 1 << 8;
      return {float(y), float(co + kOffset), float(cg + kOffset)};
    }
    case PsnrColourSpace::kYCbCr:
      break;
  }
  const double r = rgb[0], g = rgb[1], b = rgb[2];
  return {float((0.2126 * r + 0.7152 * g + 0.0722 * b) / 255.0),
          float((-0.1146 * r - 0.3854 * g + 0.5000 * b) / 255.0 + 0.5000),
          float((0.5000 * r - 0.4542 * g - 0.0458 * b) / 255.0 + 0.5000)};
}

std::array<double, 3> colour_peaks(PsnrColourSpace space) {
  switch (space) {
    case PsnrColourSpace::kRgb:
      return {255, 255, 255};
    case PsnrColourSpace::kYCoCg:
      return {255, 511, 511};
    case PsnrColourSpace::kYCbCr:
      break;
  }
  return {1, 1, 1};
}

std::array<const char*, 3> channel_names(PsnrColourSpace space) {
  switch (space) {
    case PsnrColourSpace::kRgb:
      return {"R", "G", "B"};
    case PsnrColourSpace::kYCoCg:
      return {"Y", "Co", "Cg"};
    case PsnrColourSpace::kYCbCr:
      break;
  }
  return {"Y", "Cb", "Cr"};
}

// ---- peak -------------------------------------------------------------------------------------

struct NnDistances {
  double min = DBL_MAX;
  double max = DBL_MIN;  // D: findNNdistances starts at numeric_limits<double>::min()
};

NnDistances nn_distances(const MpegCloud& a, const PsnrSearch& tree, int threads) {
  const long n = static_cast<long>(a.size());
  NnDistances out;
#pragma omp parallel num_threads(thread_count(threads))
  {
    NnDistances local;
#pragma omp for schedule(static)
    for (long i = 0; i < n; ++i) {
      std::uint32_t idx[3];
      double d2[3];
      const std::size_t found = tree.knn(a.points[i], 3, idx, d2);
      if (found < 2 || idx[0] != static_cast<std::uint32_t>(i) || d2[1] <= 0.0000000001) continue;
      const double d = std::sqrt(d2[1]);
      local.max = std::max(local.max, d);
      local.min = std::min(local.min, d);
    }
#pragma omp critical
    {
      out.max = std::max(out.max, local.max);
      out.min = std::min(out.min, local.min);
    }
  }
  return out;
}

// ---- B's normals (D: scaleNormals) ------------------------------------------------------------

/// The indices among the first `found` results at exactly the first one's distance.
std::size_t exact_ties(const std::uint32_t* idx, const double* d2, std::size_t found,
                       std::uint32_t* out) {
  std::size_t n = 0;
  for (std::size_t j = 0; j < found; ++j) {
    if (d2[0] == d2[j]) out[n++] = idx[j];
  }
  return n;
}

bool exactly_equal(double x, double y) { return x == y; }

std::vector<Point3f> transfer_normals(const MpegCloud& na, const PsnrSearch& na_tree,
                                      const MpegCloud& b, const PsnrSearch& b_tree, bool average,
                                      int threads) {
  const long n_a = static_cast<long>(na.size());
  const long n_b = static_cast<long>(b.size());
  // Each point of A's targets in B (searched in parallel, added in A's order: float sums).
  std::vector<std::array<std::uint32_t, kMaxNeighbours>> targets(static_cast<std::size_t>(n_a));
  std::vector<std::uint8_t> target_count(static_cast<std::size_t>(n_a));
#pragma omp parallel for schedule(dynamic, 1024) num_threads(thread_count(threads))
  for (long i = 0; i < n_a; ++i) {
    std::uint32_t idx[kMaxNeighbours];
    double d2[kMaxNeighbours];
    const std::size_t found =
        average ? b_tree.tie_run_knn(na.points[i], 5, true, exactly_equal, idx, d2)
                : b_tree.knn(na.points[i], 1, idx, d2);
    target_count[i] = static_cast<std::uint8_t>(
        exact_ties(idx, d2, average ? found : std::min<std::size_t>(found, 1), targets[i].data()));
  }
  std::vector<Point3f> normals(static_cast<std::size_t>(n_b), Point3f{0, 0, 0});
  std::vector<int> counts(static_cast<std::size_t>(n_b), 0);
  for (long i = 0; i < n_a; ++i) {
    for (std::size_t t = 0; t < target_count[i]; ++t) {
      const std::uint32_t j = targets[i][t];
      for (int c = 0; c < 3; ++c) normals[j][c] += na.normals[i][c];
      ++counts[j];
    }
  }
  targets = {};
#pragma omp parallel for schedule(dynamic, 1024) num_threads(thread_count(threads))
  for (long i = 0; i < n_b; ++i) {
    Point3f& n = normals[i];
    if (counts[i] > 0) {
      for (int c = 0; c < 3; ++c) n[c] = n[c] / counts[i];
      continue;
    }
    std::uint32_t idx[kMaxNeighbours];
    double d2[kMaxNeighbours];
    if (!average) {
      na_tree.knn(b.points[i], 1, idx, d2);
      n = na.normals[idx[0]];
      continue;
    }
    const std::size_t found = na_tree.tie_run_knn(b.points[i], 5, true, exactly_equal, idx, d2);
    std::uint32_t ties[kMaxNeighbours];
    const std::size_t num = exact_ties(idx, d2, found, ties);
    for (std::size_t t = 0; t < num; ++t) {
      for (int c = 0; c < 3; ++c) n[c] += na.normals[ties[t]][c];
    }
    for (int c = 0; c < 3; ++c) n[c] /= static_cast<float>(num);
  }
  return normals;
}

// ---- one direction (D: findMetric) -------------------------------------------------------------

struct PassSettings {
  bool colour = false;
  PsnrColourSpace space = PsnrColourSpace::kYCbCr;
  bool weighted = false;  // neighborsProc 2
  bool average_normals = true;
  bool keep_points = false;
  double tie_threshold = kPcErrorTieThreshold;  // D: similarPointThreshold
  LoopProgress* progress = nullptr;             // counts the points done (may be null)
};

struct PassSums {
  double d1_sum = 0, d2_sum = 0;
  double d1_max = DBL_MIN, d2_max = DBL_MIN;
  std::array<double, 3> colour_sum{0, 0, 0};
  std::array<double, 3> rgb_max{DBL_MIN, DBL_MIN, DBL_MIN};

  void add(const PassSums& o) {
    d1_sum += o.d1_sum;
    d2_sum += o.d2_sum;
    d1_max = std::max(d1_max, o.d1_max);
    d2_max = std::max(d2_max, o.d2_max);
    for (int c = 0; c < 3; ++c) {
      colour_sum[c] += o.colour_sum[c];
      rgb_max[c] = std::max(rgb_max[c], o.rgb_max[c]);
    }
  }
};

/// One point's errors: D1, D2, and the colour channels' (in the colour space).
struct PointErrors {
  double d1 = 0, d2 = 0;
  std::array<double, 3> colour{0, 0, 0};
};

struct PassOutput {
  PassSums sums;
  std::size_t points = 0;
  std::vector<PointErrors> per_point;  // per point of A (keep_points)
};

/// What the search finds for one point of A: its nearest point of B and the colour of the run of
/// neighbours tied with it (with colour).
struct PointMatch {
  std::uint32_t nearest = 0;
  Colour8 matched{0, 0, 0};
};

// One point of A searched in B: its match, and its D2 error in `d2_point` (with normals).
PointMatch match_point(const MpegCloud& a, std::size_t i, const MpegCloud& b,
                       const PsnrSearch& tree, const std::vector<Point3f>* normals,
                       const PassSettings& p, double* d2_point) {
  std::uint32_t idx[kMaxNeighbours];
  double d2[kMaxNeighbours];
  const Point3f& q = a.points[i];
  // Only the run of neighbours within the tie threshold of each other matters (D1 uses the
  // first): a 2-NN query settles most points, the full pc_error query the others.
  const bool run = p.colour || normals != nullptr;
  const double threshold = p.tie_threshold;
  const auto tied = [threshold](double x, double y) { return std::fabs(y - x) < threshold; };
  const std::size_t found =
      run ? tree.tie_run_knn(q, 10, p.average_normals, tied, idx, d2) : tree.knn(q, 1, idx, d2);
  PointMatch m;
  m.nearest = idx[0];
  std::size_t same = 1;
  if (run) {
    while (same < found && tied(d2[same - 1], d2[same])) ++same;
  }
  if (normals != nullptr) {
    double d2_sum = 0.0;
    if (p.average_normals) {
      for (std::size_t t = 0; t < same; ++t) {
        const Point3f& o = b.points[idx[t]];
        const Point3f& n = (*normals)[idx[t]];
        const float dot = (q[0] - o[0]) * n[0] + (q[1] - o[1]) * n[1] + (q[2] - o[2]) * n[2];
        d2_sum += std::pow(dot, 2.f);  // float powf, as pc_error's pow(float, float)
      }
      d2_sum /= static_cast<double>(same);
    } else {
      const Point3f& o = b.points[m.nearest];
      const Point3f& n = (*normals)[m.nearest];
      const double e0 = double(q[0]) - double(o[0]);
      const double e1 = double(q[1]) - double(o[1]);
      const double e2 = double(q[2]) - double(o[2]);
      d2_sum = e0 * n[0] + e1 * n[1] + e2 * n[2];
      d2_sum *= d2_sum;
    }
    *d2_point = d2_sum;
  }
  if (p.colour) {
    unsigned int sum[3] = {0, 0, 0};
    int merged = 0;
    for (std::size_t t = 0; t < same; ++t) {
      const int weight = p.weighted ? b.merged[idx[t]] : 1;
      for (int c = 0; c < 3; ++c) sum[c] += weight * b.colours[idx[t]][c];
      merged += weight;
    }
    for (int c = 0; c < 3; ++c) {
      m.matched[c] = static_cast<std::uint8_t>(std::round(static_cast<double>(sum[c]) / merged));
    }
  }
  return m;
}

// One point of A's errors from its match: adds them to `s` and returns them.
PointErrors point_errors(const MpegCloud& a, std::size_t i, const MpegCloud& b, const PointMatch& m,
                         const double* d2_point, const PassSettings& p, PassSums& s) {
  const Point3f& q = a.points[i];
  const Point3f& nearest = b.points[m.nearest];
  const double e0 = double(q[0]) - double(nearest[0]);
  const double e1 = double(q[1]) - double(nearest[1]);
  const double e2 = double(q[2]) - double(nearest[2]);
  PointErrors errors;
  const double d1 = e0 * e0 + e1 * e1 + e2 * e2;
  errors.d1 = d1;
  s.d1_sum += d1;
  s.d1_max = std::max(s.d1_max, d1);
  if (d2_point != nullptr) {
    errors.d2 = *d2_point;
    s.d2_sum += *d2_point;
    s.d2_max = std::max(s.d2_max, *d2_point);
  }
  if (p.colour) {
    const std::array<float, 3> in = convert(p.space, a.colours[i]);
    const std::array<float, 3> out = convert(p.space, m.matched);
    for (int c = 0; c < 3; ++c) {
      const float diff = in[c] - out[c];
      errors.colour[c] = static_cast<float>(diff * diff);
      s.colour_sum[c] += errors.colour[c];
      const int rgb = int(a.colours[i][c]) - int(m.matched[c]);
      s.rgb_max[c] = std::max(s.rgb_max[c], static_cast<double>(rgb * rgb));
    }
  }
  return errors;
}

// One direction: every point of A searched in B, its errors summed in fixed chunks of A's
// points (the same sums for any thread count). Searching in the query tree's leaf order instead
// (spatially coherent queries, the matches kept for the sums in point order) was measured: no
// faster here (the scattered reads and writes cost what the cache saves) and 8 bytes a point more.
PassOutput run_pass(const MpegCloud& a, const MpegCloud& b, const PsnrSearch& b_tree,
                    const std::vector<Point3f>* normals, const PassSettings& p, int threads) {
  PassOutput out;
  out.points = a.size();
  if (p.keep_points) out.per_point.resize(a.size());
  const long chunks = static_cast<long>((a.size() + kChunk - 1) / kChunk);
  std::vector<PassSums> partial(static_cast<std::size_t>(chunks));
#pragma omp parallel for schedule(dynamic, 1) num_threads(thread_count(threads))
  for (long c = 0; c < chunks; ++c) {
    const std::size_t first = static_cast<std::size_t>(c) * kChunk;
    const std::size_t last = std::min(a.size(), first + kChunk);
    PassSums s;
    for (std::size_t i = first; i < last; ++i) {
      double d2 = 0;
      const PointMatch m = match_point(a, i, b, b_tree, normals, p, &d2);
      const PointErrors e = point_errors(a, i, b, m, normals ? &d2 : nullptr, p, s);
      if (p.keep_points) out.per_point[i] = e;
    }
    partial[c] = s;
    if (p.progress) p.progress->add(last - first);
  }
  if (p.progress) p.progress->finish();
  for (const PassSums& s : partial) out.sums.add(s);  // in chunk order: any thread count
  return out;
}

// ---- results ------------------------------------------------------------------------------------

/// A Hausdorff value as qm3d reports it: pc_error's untouched DBL_MIN start is a zero.
double hausdorff_value(double max) { return max <= DBL_MIN ? 0.0 : max; }

double hausdorff_psnr(double h, double peak, double factor) {
  return h == 0.0 ? HUGE_VAL : psnr_of(h, peak, factor);
}

NamedValues pass_values(const PassOutput& o, double peak, bool d2, const PassSettings& p,
                        bool hausdorff) {
  const double n = static_cast<double>(o.points);
  NamedValues v;
  const double d1_mse = o.sums.d1_sum / n;
  v.emplace_back("d1_mse", d1_mse);
  v.emplace_back("d1_psnr", psnr_of(d1_mse, peak, 3));
  if (d2) {
    const double d2_mse = o.sums.d2_sum / n;
    v.emplace_back("d2_mse", d2_mse);
    v.emplace_back("d2_psnr", psnr_of(d2_mse, peak, 3));
  }
  if (hausdorff) {
    const double h1 = hausdorff_value(o.sums.d1_max);
    v.emplace_back("d1_hausdorff", h1);
    v.emplace_back("d1_hausdorff_psnr", hausdorff_psnr(h1, peak, 3));
    if (d2) {
      const double h2 = hausdorff_value(o.sums.d2_max);
      v.emplace_back("d2_hausdorff", h2);
      v.emplace_back("d2_hausdorff_psnr", hausdorff_psnr(h2, peak, 3));
    }
  }
  if (!p.colour) return v;
  const std::array<double, 3> peaks = colour_peaks(p.space);
  std::array<double, 3> mse;
  for (int c = 0; c < 3; ++c) {
    mse[c] = o.sums.colour_sum[c] / n;
    v.emplace_back("c" + std::to_string(c) + "_mse", mse[c]);
  }
  for (int c = 0; c < 3; ++c)
    v.emplace_back("c" + std::to_string(c) + "_psnr", psnr_of(mse[c], peaks[c]));
  if (!hausdorff) return v;
  std::array<double, 3> h;
  for (int c = 0; c < 3; ++c) {
    h[c] = hausdorff_value(o.sums.rgb_max[c]);
    v.emplace_back("c" + std::to_string(c) + "_hausdorff", h[c]);
  }
  for (int c = 0; c < 3; ++c) {
    v.emplace_back("c" + std::to_string(c) + "_hausdorff_psnr", hausdorff_psnr(h[c], 255.0, 1));
  }
  return v;
}

/// pc_error's "3. Final (symmetric)": the larger error and the smaller PSNR of each value.
NamedValues symmetric_values(const NamedValues& a, const NamedValues& b) {
  NamedValues out;
  for (const auto& [name, va] : a) {
    const double vb = *find_value(b, name);
    const bool quality = name.size() > 5 && name.compare(name.size() - 5, 5, "_psnr") == 0;
    out.emplace_back(name, quality ? std::min(va, vb) : std::max(va, vb));
  }
  return out;
}

// per_element: each input point's D1 error (a merged duplicate takes its run's);
// per_element_values: its D2 error (with normals) and colour errors (with colour).
DirectionResult direction_result(const NamedValues& values, const PassOutput& o,
                                 const MpegCloud& iterated, bool per_element, bool d2,
                                 bool colour) {
  DirectionResult d;
  d.score = *find_value(values, "d1_psnr");
  d.features.fill(0.0);
  d.values = values;
  if (!per_element) return d;
  const std::size_t n = iterated.of_input.size();
  const auto on_input = [&](auto&& pick) {
    std::vector<double> v(n);
    for (std::size_t k = 0; k < n; ++k) v[k] = pick(o.per_point[iterated.of_input[k]]);
    return v;
  };
  d.per_element = on_input([](const PointErrors& e) { return e.d1; });
  if (d2)
    d.per_element_values.emplace_back("d2", on_input([](const PointErrors& e) { return e.d2; }));
  for (int c = 0; colour && c < 3; ++c) {
    d.per_element_values.emplace_back("c" + std::to_string(c),
                                      on_input([c](const PointErrors& e) { return e.colour[c]; }));
  }
  return d;
}

// ---- checks -------------------------------------------------------------------------------------

// The checks of a cloud's points and colours (`Point`: Vec3 as read, or Point3f from psnr's own
// reader: the same values, the same messages).
template <class Point>
void check_cloud(const std::vector<Point>& positions, std::size_t colours, const std::string& name,
                 bool colour) {
  if (positions.empty()) throw NumericError("psnr: " + name + ": the cloud is empty");
  for (std::size_t i = 0; i < positions.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const double v = positions[i][k];
      if (!std::isfinite(v) || std::fabs(v) > FLT_MAX) {
        throw NumericError("psnr: " + name + ": point " + std::to_string(i) +
                           " has a coordinate that is not a finite float32 (" + short_number(v) +
                           ")");
      }
    }
  }
  for (int k = 0; k < 3; ++k) {
    const auto [lo, hi] =
        std::minmax_element(positions.begin(), positions.end(),
                            [k](const Point& a, const Point& b) { return a[k] < b[k]; });
    if (!std::isfinite(static_cast<float>((*hi)[k]) - static_cast<float>((*lo)[k]))) {
      throw NumericError("psnr: " + name + ": the cloud spans more than float32 can hold (" +
                         short_number((*lo)[k]) + " to " + short_number((*hi)[k]) +
                         "; pc_error's distances overflow): scale the cloud down");
    }
  }
  if (colour && colours == 0) {
    throw FormatError(name +
                      ": no vertex colours (psnr's colour values need one colour per point; "
                      "give --no-color for geometry only)");
  }
  if (colour && colours != positions.size()) {
    throw FormatError(name + ": " + std::to_string(positions.size()) + " points but " +
                      std::to_string(colours) + " colours");
  }
}

template <class Point>
void check_normals(const std::vector<Point>& normals, std::size_t points, const std::string& name) {
  if (normals.empty()) return;
  if (normals.size() != points) {
    throw FormatError(name + ": " + std::to_string(normals.size()) + " normals for " +
                      std::to_string(points) + " reference points (one normal per point needed)");
  }
  for (std::size_t i = 0; i < normals.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const double v = normals[i][k];
      if (!std::isfinite(v) || std::fabs(v) > FLT_MAX) {
        throw FormatError(name + ": the normal of point " + std::to_string(i) + " is not finite (" +
                          short_number(v) + ")");
      }
    }
  }
}

/// Warns when the normals D2 projects on are not unit length: pc_error uses them as given, so
/// D2 scales with their squared length (zero normals: D2 = 0 and an infinite PSNR; huge ones:
/// float32 overflow, an infinite D2).
void warn_of_normal_lengths(const std::vector<Point3f>& normals, const std::string& name,
                            std::vector<std::string>& warnings) {
  // Lengths within 1 % of 1 are unit normals written with few digits.
  constexpr double kUnitTolerance = 0.01;
  std::size_t off = 0;
  double shortest = HUGE_VAL, longest = 0;
  for (const Point3f& n : normals) {
    const double len = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
    if (std::fabs(len - 1.0) <= kUnitTolerance) continue;
    ++off;
    shortest = std::min(shortest, len);
    longest = std::max(longest, len);
  }
  if (off == 0) return;
  warnings.push_back("psnr: " + name + ": " + std::to_string(off) + " of " +
                     std::to_string(normals.size()) + " normals are not unit length (" +
                     short_number(shortest) + " to " + short_number(longest) +
                     "): as pc_error, D2 uses them as given, so it scales with their squared "
                     "length (zero normals give D2 = 0, huge ones overflow float32); normalise "
                     "them (or --normals estimate)");
}

/// Warns of each error value that is not finite (float32 overflow in pc_error's arithmetic).
void warn_of_non_finite(const NamedValues& values, std::vector<std::string>& warnings) {
  for (const auto& [name, v] : values) {
    const bool error_value = name.size() < 5 || name.compare(name.size() - 5, 5, "_psnr") != 0;
    if (!error_value || std::isfinite(v)) continue;
    warnings.push_back("psnr: " + name + " is " + short_number(v) +
                       ": float32 overflow in pc_error's arithmetic (coordinates or normals too "
                       "large); scale the inputs down");
  }
}

/// pc_error's tie threshold is absolute (a squared distance): once it is not small against the
/// squared point spacing, neighbours at different distances count as tied (their colours
/// averaged, D2 averaged over them), so the values depend on the unit.
constexpr double kTieWarningShare = 1e-3;

void warn_of_tie_threshold(double threshold, double spacing, const std::string& name,
                           const std::string& tool, std::vector<std::string>& warnings) {
  if (!(threshold > kTieWarningShare * spacing * spacing)) return;
  warnings.push_back("psnr: " + name + ": its point spacing (" + short_number(spacing) +
                     ") is so small that " + tool + "'s absolute tie threshold (" +
                     short_number(threshold) +
                     " on squared distances) treats neighbours at different distances as "
                     "tied, as " +
                     tool +
                     " does: colour and D2 values depend on the unit; "
                     "scale the inputs up (e.g. to millimetres) for unit-independent values");
}

/// The readers' typical point spacing: bounding-box diagonal / sqrt(points).
double typical_spacing(const BoundingBox& box, std::size_t points) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) d2 += (box.max[k] - box.min[k]) * (box.max[k] - box.min[k]);
  return std::sqrt(d2) / std::sqrt(static_cast<double>(points));
}

/// The warning of coordinates far from the origin for pc_error's float32 arithmetic (none: "").
template <class Point>
std::string far_from_origin_warning(const std::vector<Point>& positions, const std::string& name) {
  BoundingBox box{{positions[0][0], positions[0][1], positions[0][2]},
                  {positions[0][0], positions[0][1], positions[0][2]}};
  for (const Point& p : positions) {
    for (int k = 0; k < 3; ++k) {
      box.min[k] = std::min<double>(box.min[k], p[k]);
      box.max[k] = std::max<double>(box.max[k], p[k]);
    }
  }
  return float32_precision_warning(box.min, box.max, typical_spacing(box, positions.size()),
                                   "typical point spacing, box diagonal / sqrt(points)",
                                   "psnr: " + name, "pc_error");
}

/// --normals estimate: ../shared/tools/add_pca_normals.py's normals (float32, as it writes them).
std::vector<Vec3> estimated_normals(const std::vector<Vec3>& positions, int threads) {
  const std::vector<std::array<float, 3>> f = detail::estimate_pca_normals(positions, threads);
  std::vector<Vec3> out(f.size());
  for (std::size_t i = 0; i < f.size(); ++i) out[i] = {f[i][0], f[i][1], f[i][2]};
  return out;
}

std::string text_note(const NamedValues& v, const PsnrOptions& o, double peak,
                      const std::string& peak_source) {
  std::ostringstream out;
  const auto value = [&](const char* name) { return short_number(*find_value(v, name)); };
  out << "[D1 " << value("d1_psnr") << " dB";
  if (find_value(v, "d2_psnr")) out << ", D2 " << value("d2_psnr") << " dB";
  if (o.colour) {
    const auto names = channel_names(o.colour_space);
    for (int c = 0; c < 3; ++c) {
      out << ", " << names[c] << ' ' << value(("c" + std::to_string(c) + "_psnr").c_str()) << " dB";
    }
  }
  out << "; peak " << short_number(peak) << " (" << peak_source << ")]";
  return out.str();
}

}  // namespace

namespace {

constexpr const char* kPcErrorTool = "MPEG pc_error 0.14.2 (MPEGGroup/mpeg-pcc-dmetric @ bd6df59)";
constexpr const char* kMmetricTool = "MPEG mmetric 1.1.7 (MPEGGroup/mpeg-pcc-mmetric @ 5faa660)";

/// How the loaded clouds are compared: pc_error's rules, or mmetric's compare --mode pcc.
struct Conventions {
  const char* tool = "pc_error";
  double tie_threshold = kPcErrorTieThreshold;
  D2Normals d2_normals = D2Normals::kTransferred;
};

/// Everything after loading: trees, peak, B's normals, both passes, the result. `na` holds the
/// normals of D2 (pc_error's cloudNormalsA: `a` itself, or a normals file's cloud); `peak` the
/// peak when fixed (else pc_error's nearest-neighbour default). Adds to `result` and `details`.
void compare_loaded(const MpegCloud& a, const MpegCloud& b, const MpegCloud& na,
                    std::optional<double> peak_given, const PsnrOptions& options,
                    const Conventions& conventions, const std::string& reference_name,
                    ProgressSteps& progress, nlohmann::json& details, MetricResult& result) {
  const Direction direction = options.direction.value_or(Direction::kSymmetric);
  const bool own_normals = conventions.d2_normals == D2Normals::kOwn && !b.normals.empty();
  const bool d2 = !na.normals.empty();

  progress.begin("trees");
  // Each cloud's search (psnr_search.h: a grid, pc_error's tree where needed), built
  // concurrently; a sample of the queries decides between them.
  const double threshold = conventions.tie_threshold;
  auto a_tree_task =
      std::async(options.threads == 1 ? std::launch::deferred : std::launch::async,
                 [&] { return std::make_unique<PsnrSearch>(a.points, &b.points, threshold); });
  const PsnrSearch b_tree(b.points, &a.points, threshold);
  const std::unique_ptr<PsnrSearch> a_tree_owned = a_tree_task.get();
  const PsnrSearch& a_tree = *a_tree_owned;
  const bool na_is_a = &na == &a || na.points == a.points;
  const std::unique_ptr<PsnrSearch> na_tree =
      d2 && !own_normals && !na_is_a ? std::make_unique<PsnrSearch>(na.points, &b.points, threshold)
                                     : nullptr;

  double peak = 0;
  if (peak_given) {
    peak = *peak_given;
  } else {
    const NnDistances nn = nn_distances(a, a_tree, options.threads);
    if (nn.max <= DBL_MIN) {
      throw NumericError("psnr: " + reference_name +
                         ": no point has a nearest neighbour farther than pc_error's absolute "
                         "1e-5 (no two distinct points, or a spacing below 1e-5 in the file's "
                         "units), so no peak; give --peak or scale the clouds up");
    }
    peak = nn.max;
    if (options.colour || d2) {
      warn_of_tie_threshold(conventions.tie_threshold, nn.max, reference_name, conventions.tool,
                            result.warnings);
    }
    details["nn_min"] = nn.min;
    details["nn_max"] = nn.max;
  }
  details["peak"] = peak;
  details["points_reference"] = a.size();
  details["points_distorted"] = b.size();
  details["duplicates_reference"] = a.duplicates;
  details["duplicates_distorted"] = b.duplicates;
  if (d2)
    details["d2_normals"] = own_normals ? "distorted's own" : "transferred from the reference";

  progress.begin("normals");
  std::vector<Point3f> b_normals;
  if (d2 && !own_normals) {
    b_normals = transfer_normals(na, na_tree ? *na_tree : a_tree, b, b_tree,
                                 options.average_normals, options.threads);
  }
  const std::vector<Point3f>& b_d2_normals = own_normals ? b.normals : b_normals;

  progress.begin("errors");
  PassSettings p;
  p.colour = options.colour;
  p.space = options.colour_space;
  p.weighted = options.tied == TiedNeighbours::kWeightedAverage;
  p.average_normals = options.average_normals;
  p.keep_points = options.per_element;
  p.tie_threshold = conventions.tie_threshold;
  LoopProgress errors_done(&progress, (direction != Direction::kDistToRef ? a.size() : 0) +
                                          (direction != Direction::kRefToDist ? b.size() : 0));
  p.progress = &errors_done;
  std::optional<NamedValues> ab, ba;
  if (direction != Direction::kDistToRef) {
    const PassOutput o = run_pass(a, b, b_tree, d2 ? &b_d2_normals : nullptr, p, options.threads);
    ab = pass_values(o, peak, d2, p, options.hausdorff);
    result.ref_to_dist = direction_result(*ab, o, a, options.per_element, d2, options.colour);
  }
  if (direction != Direction::kRefToDist) {
    const PassOutput o = run_pass(b, a, a_tree, d2 ? &na.normals : nullptr, p, options.threads);
    ba = pass_values(o, peak, d2, p, options.hausdorff);
    result.dist_to_ref = direction_result(*ba, o, b, options.per_element, d2, options.colour);
  }
  result.values = ab && ba ? symmetric_values(*ab, *ba) : ab ? *ab : *ba;
  warn_of_non_finite(result.values, result.warnings);
  result.score = *find_value(result.values, "d1_psnr");
  // The source the caller recorded: a mesh's peak is computed (the box diagonal), not given.
  result.text_note =
      text_note(result.values, options, peak, details.at("peak_source").get<std::string>());
}

void check_peak(const std::optional<double>& peak) {
  if (peak && !(*peak > 0 && *peak <= FLT_MAX)) {
    throw std::invalid_argument("peak: must be a positive float32 number, got " +
                                short_number(*peak));
  }
}

// The provenance and details every psnr result ends with, the progress line closed.
MetricResult finished(MetricResult result, nlohmann::json details, const char* tool,
                      std::chrono::steady_clock::time_point start, ProgressSteps& progress) {
  result.details = std::move(details);
  result.provenance.reproduces = tool;
  result.provenance.version = kVersion;
  result.provenance.seconds = seconds_since(start);
  progress.finish();
  return result;
}

}  // namespace

namespace {

/// A pc_error comparison's inputs once checked and rounded to float32. `a.normals`: the
/// reference's own normals (or estimated); `normals_file`: a separate normals file (pc_error -n;
/// its positions empty when there is none).
struct FloatInputs {
  detail::FloatCloud a, b;
  const ReferenceNormals* normals_file = nullptr;
};

/// Everything from loading on (compute_psnr and psnr's own file reader): the two clouds loaded
/// (concurrently, each freed as it is sorted) and compared.
MetricResult psnr_of_floats(FloatInputs in, const PsnrOptions& options,
                            const std::string& reference_name, MetricResult result,
                            ProgressSteps& progress, std::chrono::steady_clock::time_point start) {
  const bool separate = in.normals_file != nullptr && !in.normals_file->positions.empty();
  const std::string normals_name = separate ? in.normals_file->name : reference_name;
  detail::LoadRules rules;
  rules.duplicates = static_cast<int>(options.duplicates);
  rules.weighted = options.tied == TiedNeighbours::kWeightedAverage;
  rules.keep_of_input = options.per_element;
  auto a_task = std::async(options.threads == 1 ? std::launch::deferred : std::launch::async,
                           [&] { return detail::load_mpeg_cloud(std::move(in.a), rules); });
  const MpegCloud b = detail::load_mpeg_cloud(std::move(in.b), rules);
  const MpegCloud a = a_task.get();
  // A normals file is a cloud of its own (pc_error loads it with the same duplicate rule).
  std::optional<MpegCloud> file_normals;
  if (separate) {
    detail::LoadRules file_rules = rules;
    file_rules.weighted = false;
    file_normals = detail::load_mpeg_cloud(
        detail::float_cloud(in.normals_file->positions, nullptr, in.normals_file->normals),
        file_rules);
  }
  if (file_normals && file_normals->size() != a.size()) {
    throw FormatError(normals_name + ": " + std::to_string(file_normals->size()) +
                      " points (after duplicates) for the reference's " + std::to_string(a.size()) +
                      " (--normals needs one normal per reference point)");
  }
  if (file_normals && file_normals->points != a.points) {
    result.warnings.push_back("psnr: " + normals_name +
                              ": its points are not the reference's; "
                              "as pc_error, its normals are paired with the reference's points "
                              "by their order after sorting");
  }
  if (options.inputs_done) options.inputs_done();
  const MpegCloud& na = file_normals ? *file_normals : a;  // pc_error's cloudNormalsA
  if (!options.estimate_normals) warn_of_normal_lengths(na.normals, normals_name, result.warnings);
  if (na.normals.empty()) {
    result.warnings.push_back("psnr: " + reference_name +
                              " has no normals (nx, ny, nz): D2 is left out, as pc_error does "
                              "(give --normals FILE or --normals estimate)");
  }
  nlohmann::json details = nlohmann::json::object();
  // pc_error's -r is a float.
  const std::optional<double> peak =
      options.peak ? std::optional<double>(static_cast<float>(*options.peak)) : std::nullopt;
  details["peak_source"] =
      options.peak ? "given" : "largest nearest-neighbour distance in the reference";
  compare_loaded(a, b, na, peak, options, Conventions{}, reference_name, progress, details, result);
  return finished(std::move(result), std::move(details), kPcErrorTool, start, progress);
}

/// The checks and warnings before loading, on the points as read (`Point`: Vec3 or Point3f).
template <class Point>
void check_inputs(const std::vector<Point>& reference, std::size_t reference_colours,
                  const std::vector<Point>& distorted, std::size_t distorted_colours,
                  const PsnrOptions& options, const std::string& reference_name,
                  const std::string& distorted_name, std::vector<std::string>& warnings) {
  check_thread_count(options.threads);
  check_peak(options.peak);
  check_cloud(reference, reference_colours, reference_name, options.colour);
  check_cloud(distorted, distorted_colours, distorted_name, options.colour);
  for (const auto& [cloud, name] :
       {std::pair{&reference, &reference_name}, std::pair{&distorted, &distorted_name}}) {
    const std::string w = far_from_origin_warning(*cloud, *name);
    if (!w.empty()) warnings.push_back(w);
  }
}

/// The reference's own normals (`own`, as read) checked, or with --normals estimate computed,
/// as float32; a normals file's are checked here and loaded with the clouds.
template <class Point>
std::vector<Point3f> own_normals(const std::vector<Point>& positions, const std::vector<Point>& own,
                                 const ReferenceNormals& file, const PsnrOptions& options,
                                 const std::string& reference_name) {
  if (options.estimate_normals) {
    std::vector<Vec3> p(positions.size());
    for (std::size_t i = 0; i < p.size(); ++i)
      p[i] = {positions[i][0], positions[i][1], positions[i][2]};
    const std::vector<Vec3> estimated = estimated_normals(p, options.threads);
    check_normals(estimated, positions.size(), reference_name);
    return detail::float_cloud({}, nullptr, estimated).normals;
  }
  if (!file.positions.empty()) {
    check_normals(file.normals, file.positions.size(), file.name);
    return {};
  }
  check_normals(own, positions.size(), reference_name);
  std::vector<Point3f> out(own.size());
  for (std::size_t i = 0; i < own.size(); ++i) {
    for (int k = 0; k < 3; ++k) out[i][k] = static_cast<float>(own[i][k]);
  }
  return out;
}

}  // namespace

MetricResult compute_psnr(const ColoredCloud& reference, const ReferenceNormals& reference_normals,
                          const ColoredCloud& distorted, const PsnrOptions& options,
                          const std::string& reference_name, const std::string& distorted_name) {
  const auto start = std::chrono::steady_clock::now();
  MetricResult result;
  result.metric = "psnr";
  check_inputs(reference.positions, reference.colors.size(), distorted.positions,
               distorted.colors.size(), options, reference_name, distorted_name, result.warnings);
  ProgressSteps progress(options.progress, 4);
  progress.begin("loading");
  FloatInputs in;
  in.a = detail::float_cloud(reference.positions, options.colour ? &reference.colors : nullptr, {});
  in.a.normals = own_normals(reference.positions, reference_normals.normals, reference_normals,
                             options, reference_name);
  in.b = detail::float_cloud(distorted.positions, options.colour ? &distorted.colors : nullptr, {});
  in.normals_file = options.estimate_normals ? nullptr : &reference_normals;
  return psnr_of_floats(std::move(in), options, reference_name, std::move(result), progress, start);
}

namespace {

/// compute_psnr on two clouds as psnr's own reader gives them (psnr_reader.h).
MetricResult psnr_of_files(detail::FloatCloudFile reference, const ReferenceNormals& normals_file,
                           detail::FloatCloudFile distorted, const PsnrOptions& options,
                           const std::string& reference_name, const std::string& distorted_name) {
  const auto start = std::chrono::steady_clock::now();
  MetricResult result;
  result.metric = "psnr";
  const detail::FloatCloud& a = reference.cloud;
  const detail::FloatCloud& b = distorted.cloud;
  check_inputs(a.positions, a.colours.size(), b.positions, b.colours.size(), options,
               reference_name, distorted_name, result.warnings);
  ProgressSteps progress(options.progress, 4);
  progress.begin("loading");
  FloatInputs in;
  in.a.normals = own_normals(a.positions, a.normals, normals_file, options, reference_name);
  in.a.positions = std::move(reference.cloud.positions);
  if (options.colour) in.a.colours = std::move(reference.cloud.colours);
  in.b.positions = std::move(distorted.cloud.positions);
  if (options.colour) in.b.colours = std::move(distorted.cloud.colours);
  reference = {};
  distorted = {};
  in.normals_file = options.estimate_normals ? nullptr : &normals_file;
  return psnr_of_floats(std::move(in), options, reference_name, std::move(result), progress, start);
}

}  // namespace

namespace {

/// Grid samples as the cloud loader takes them (float32 values exactly; colours u / 255).
struct SampledCloud {
  ColoredCloud cloud;
  std::vector<Vec3> normals;
};

SampledCloud as_cloud(const GridSamples& s) {
  SampledCloud out;
  const std::size_t n = s.positions.size();
  out.cloud.positions.resize(n);
  out.normals.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      out.cloud.positions[i][k] = s.positions[i][k];
      out.normals[i][k] = s.normals[i][k];
    }
  }
  out.cloud.colors.resize(s.colours.size());
  for (std::size_t i = 0; i < s.colours.size(); ++i) {
    out.cloud.colors[i] = {s.colours[i][0] / 255.0, s.colours[i][1] / 255.0,
                           s.colours[i][2] / 255.0};
  }
  return out;
}

/// mmetric's --resolution 0: glm::length(max - min) of the sampled cloud A's float box.
double box_diagonal(const std::vector<Float3>& points) {
  const FloatBox b = vertex_box(points);
  const float d0 = b.max[0] - b.min[0], d1 = b.max[1] - b.min[1], d2 = b.max[2] - b.min[2];
  const float t0 = d0 * d0, t1 = d1 * d1, t2 = d2 * d2;
  return std::sqrt(t0 + t1 + t2);
}

nlohmann::json box_json(const FloatBox& b) {
  return {{"min", {b.min[0], b.min[1], b.min[2]}}, {"max", {b.max[0], b.max[1], b.max[2]}}};
}

nlohmann::json sampling_json(const GridSamples& s) {
  return {{"samples", s.positions.size()},
          {"duplicate_samples_dropped", s.duplicate_samples},
          {"degenerate_faces_skipped", s.degenerate_faces}};
}

}  // namespace

MetricResult compute_mesh_psnr(const Input& reference, const Input& distorted,
                               const GridSampler& sampler, const MeshPsnrOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  check_thread_count(options.threads);
  check_peak(options.peak);
  if (!sampler) throw std::logic_error("psnr: no grid sampler (the mesh module is not linked)");
  if (options.estimate_normals) {
    throw std::invalid_argument(
        "normals: two meshes are compared on their samples' face "
        "normals; --normals does not apply to meshes");
  }
  for (const Input* in : {&reference, &distorted}) {
    if (!in->is_mesh()) {
      throw FormatError(in->name() +
                        ": a point cloud; psnr compares two meshes (sampled on one "
                        "grid) or two clouds, not a mesh with a cloud (sample the mesh first: "
                        "qm3d sample --mode grid)");
    }
  }
  ProgressSteps progress(options.progress, 5);
  MetricResult result;
  result.metric = "psnr";

  progress.begin("sampling");
  GridSamplingOptions g;
  g.grid_size = options.grid_size;
  g.box = options.box ? *options.box
                      : union_box(vertex_box(reference.mesh().mesh.positions),
                                  vertex_box(distorted.mesh().mesh.positions));
  g.bilinear = options.bilinear;
  g.threads = options.threads;
  const FloatBox& fb = *g.box;
  const float grid_step =
      std::max({fb.max[0] - fb.min[0], fb.max[1] - fb.min[1], fb.max[2] - fb.min[2]}) /
      static_cast<float>(options.grid_size - 1);
  const std::string far = float32_precision_warning(
      Vec3{fb.min[0], fb.min[1], fb.min[2]}, Vec3{fb.max[0], fb.max[1], fb.max[2]}, grid_step,
      "grid step", "psnr: " + reference.name() + ", " + distorted.name(), "mmetric");
  if (!far.empty()) result.warnings.push_back(far);
  GridSamples sa = sampler(reference, g);
  GridSamples sb = sampler(distorted, g);
  for (const auto& [s, in] : {std::pair{&sa, &reference}, std::pair{&sb, &distorted}}) {
    for (const std::string& w : s->warnings) result.warnings.push_back(in->name() + ": " + w);
  }
  PsnrOptions o = options;
  if (o.colour && (sa.colours.empty() || sb.colours.empty())) {
    const std::string& name = sa.colours.empty() ? reference.name() : distorted.name();
    result.warnings.push_back("psnr: " + name +
                              " has no vertex colours: geometry values only "
                              "(as mmetric)");
    o.colour = false;
  }
  nlohmann::json details = nlohmann::json::object();
  details["sampling"] = {{"method", "mmetric grid (mm sample --mode grid --useNormal)"},
                         {"grid_size", options.grid_size},
                         {"box", box_json(sa.box)},
                         {"box_source", options.box ? "given" : "union of the two vertex boxes"},
                         {"step", sa.step},
                         {"reference", sampling_json(sa)},
                         {"distorted", sampling_json(sb)}};
  details["conventions"] = {{"tool", "mmetric 1.1.7 compare --mode pcc"},
                            {"tie_threshold", kMmetricTieThreshold},
                            {"duplicate_normals", "averaged (unnormalised)"}};
  const std::optional<double> peak = options.peak ? static_cast<float>(*options.peak)
                                                  : static_cast<float>(box_diagonal(sa.positions));
  details["peak_source"] = options.peak
                               ? "given"
                               : "diagonal of the reference's sampled cloud's box, mmetric's "
                                 "--resolution 0";
  const int dups = static_cast<int>(o.duplicates);
  const bool weighted = o.tied == TiedNeighbours::kWeightedAverage;

  progress.begin("loading");
  // mmetric's convertModel + removeDuplicatePoints; the samples are freed as each is loaded.
  const auto load = [&](GridSamples& samples) {
    const SampledCloud c = as_cloud(samples);
    samples = {};
    return detail::load_mpeg_cloud(c.cloud.positions, o.colour ? &c.cloud.colors : nullptr,
                                   c.normals, dups, weighted, true);
  };
  const MpegCloud a = load(sa);
  const MpegCloud b = load(sb);
  if (options.inputs_done) options.inputs_done();
  Conventions c;
  c.tool = "mmetric";
  c.tie_threshold = kMmetricTieThreshold;
  c.d2_normals = options.d2_normals;
  compare_loaded(a, b, a, peak, o, c, reference.name(), progress, details, result);
  return finished(std::move(result), std::move(details), kMmetricTool, start, progress);
}

// mmetric 1.1.7's compare --mode pcc on two clouds (mmCompare.cpp Compare::pcc; the rules in
// shared/data/reference/mpeg/clouds_pcc/README.md): both clouds loaded with their normals and
// duplicates merged as for meshes (normals averaged, not renormalised); peak = A's box diagonal
// before merging (float32); D2 only when A has normals, the pass A -> B on B's own normals when B
// has them (--normalCalcModificationEnable, its default), else transferred from A; ties 1e-20.
MetricResult compute_psnr_mmetric(const ColoredCloud& reference,
                                  const std::vector<Vec3>& reference_normals,
                                  const ColoredCloud& distorted,
                                  const std::vector<Vec3>& distorted_normals,
                                  const PsnrOptions& options, D2Normals d2_normals,
                                  const std::string& reference_name,
                                  const std::string& distorted_name) {
  const auto start = std::chrono::steady_clock::now();
  check_thread_count(options.threads);
  check_peak(options.peak);
  check_cloud(reference.positions, reference.colors.size(), reference_name, options.colour);
  check_cloud(distorted.positions, distorted.colors.size(), distorted_name, options.colour);
  check_normals(reference_normals, reference.positions.size(), reference_name);
  check_normals(distorted_normals, distorted.positions.size(), distorted_name);
  ProgressSteps progress(options.progress, 4);
  MetricResult result;
  result.metric = "psnr";

  progress.begin("loading");
  const int dups = static_cast<int>(options.duplicates);
  const bool weighted = options.tied == TiedNeighbours::kWeightedAverage;
  const auto load = [&](const ColoredCloud& c, const std::vector<Vec3>& normals) {
    return detail::load_mpeg_cloud(c.positions, options.colour ? &c.colors : nullptr, normals, dups,
                                   weighted, true);
  };
  const MpegCloud a = load(reference, reference_normals);
  const MpegCloud b = load(distorted, distorted_normals);
  std::vector<Float3> a_points(reference.positions.size());
  for (std::size_t i = 0; i < a_points.size(); ++i) {
    for (int k = 0; k < 3; ++k) a_points[i][k] = static_cast<float>(reference.positions[i][k]);
  }
  if (options.inputs_done) options.inputs_done();
  const float diagonal = static_cast<float>(box_diagonal(a_points));
  if (!options.peak && !(diagonal > 0)) {
    throw NumericError("psnr: " + reference_name +
                       ": its box has no extent, so its diagonal "
                       "gives no peak; give --peak");
  }
  const double peak = options.peak ? static_cast<float>(*options.peak) : diagonal;
  if (a.normals.empty()) {
    result.warnings.push_back("psnr: " + reference_name +
                              " has no normals (nx, ny, nz): D2 is left out, as mmetric does");
  }
  nlohmann::json details = nlohmann::json::object();
  details["conventions"] = {{"tool", "mmetric 1.1.7 compare --mode pcc"},
                            {"tie_threshold", kMmetricTieThreshold},
                            {"duplicate_normals", "averaged (unnormalised)"}};
  details["peak_source"] = options.peak ? "given"
                                        : "diagonal of the reference's box (mmetric's "
                                          "--resolution 0)";
  Conventions c;
  c.tie_threshold = kMmetricTieThreshold;
  c.d2_normals = d2_normals;
  compare_loaded(a, b, a, peak, options, c, reference_name, progress, details, result);
  return finished(std::move(result), std::move(details), kMmetricTool, start, progress);
}

// ---- the registry entry -------------------------------------------------------------------------

namespace {

PsnrColourSpace parse_colour_space(const std::string& name) {
  if (name == "rgb") return PsnrColourSpace::kRgb;
  if (name == "ycocg") return PsnrColourSpace::kYCoCg;
  return PsnrColourSpace::kYCbCr;
}

// --normals FILE: the file's points and normals (a PLY with nx, ny, nz: pc_error -n).
ReferenceNormals normals_file(const std::string& path) {
  CloudData c = read_cloud_data(path, CloudFormat::kPly);
  if (c.normals.empty()) {
    throw FormatError(path +
                      ": no normals (nx, ny, nz vertex properties), which --normals FILE "
                      "needs");
  }
  return ReferenceNormals{std::move(c.normals), std::move(c.cloud.positions), path};
}

// Each line of `a`, then those of `b` not in `a` (two inputs' reader warnings: the same file may
// be both).
std::vector<std::string> merged_lines(std::vector<std::string> a,
                                      const std::vector<std::string>& b) {
  for (const std::string& w : b) {
    if (std::find(a.begin(), a.end(), w) == a.end()) a.push_back(w);
  }
  return a;
}

// What run_metric does for a metric that does not read its files: both inputs read as `kind`
// (concurrently unless one thread was asked for), their coordinate range checked; returns the
// cloud readers' warnings.
std::vector<std::string> read_inputs(const Input& ref, const Input& dist, Input::Kind kind,
                                     int threads) {
  auto ref_task = std::async(threads == 1 ? std::launch::deferred : std::launch::async,
                             [&] { ref.load(kind); });
  dist.load(kind);
  ref_task.get();
  const bool clouds = kind == Input::Kind::kCloud;
  const std::vector<std::string> reading =
      clouds ? merged_lines(ref.cloud_warnings(), dist.cloud_warnings())
             : std::vector<std::string>{};
  for (const Input* in : {&ref, &dist}) {
    check_coordinate_range(clouds ? in->cloud().positions : in->mesh().mesh.positions, in->name());
  }
  return reading;
}

bool own_reader_may_read(const Input& in) {
  return !in.is_mesh() && in.format() == FileFormat::kPly && !in.path().empty() &&
         in.path().string() == in.name();  // not a spooled pipe
}

// Both clouds read by psnr's own reader, or nullopt when it does not apply to one of them. Its
// values are float32 (no coordinate reaches check_coordinate_range's limits).
std::optional<std::pair<detail::FloatCloudFile, detail::FloatCloudFile>> read_own(const Input& ref,
                                                                                  const Input& dist,
                                                                                  int threads) {
  if (!own_reader_may_read(ref) || !own_reader_may_read(dist)) return std::nullopt;
  auto ref_task = std::async(threads == 1 ? std::launch::deferred : std::launch::async,
                             [&] { return detail::read_float_ply(ref.path()); });
  std::optional<detail::FloatCloudFile> b = detail::read_float_ply(dist.path());
  std::optional<detail::FloatCloudFile> a = ref_task.get();
  if (!a || !b) return std::nullopt;
  return std::pair{std::move(*a), std::move(*b)};
}

/// The options of a run (--peak, --color-space, ...) as compute_psnr / compute_mesh_psnr take
/// them.
MeshPsnrOptions psnr_options(const RunOptions& run, const OptionValues& v) {
  MeshPsnrOptions o;
  static_cast<RunOptions&>(o) = run;
  const double peak = v.at("peak").get<double>();
  if (peak > 0) o.peak = peak;
  o.colour_space = parse_colour_space(v.at("color_space").get<std::string>());
  o.duplicates = static_cast<DuplicatePoints>(v.at("drop_duplicates").get<int>());
  o.tied = static_cast<TiedNeighbours>(v.at("neighbours").get<int>());
  o.average_normals = v.at("average_normals").get<bool>();
  o.hausdorff = !v.at("no_hausdorff").get<bool>();
  o.colour = !v.at("no_color").get<bool>();
  o.estimate_normals = v.at("normals").get<std::string>() == "estimate";
  return o;
}

/// Two PLY clouds of the common layout compared by pc_error's rules, read by psnr's own reader
/// straight to float32 (psnr_reader.h); nullopt when it does not apply (read_inputs then).
std::optional<MetricResult> run_on_own_reads(const Input& ref, const Input& dist,
                                             const PsnrOptions& o, const OptionValues& v) {
  const std::string normals = v.at("normals").get<std::string>();
  if (ref.is_mesh() || dist.is_mesh() || v.at("conventions").get<std::string>() == "mmetric" ||
      v.at("d2_normals").get<std::string>() == "own") {
    return std::nullopt;
  }
  auto files = read_own(ref, dist, o.threads);
  if (!files) return std::nullopt;
  const std::vector<std::string> reading =
      merged_lines(files->first.warnings, files->second.warnings);
  const ReferenceNormals given =
      normals.empty() || o.estimate_normals ? ReferenceNormals{} : normals_file(normals);
  const bool own = !files->first.cloud.normals.empty();
  MetricResult r = psnr_of_files(std::move(files->first), given, std::move(files->second), o,
                                 ref.name(), dist.name());
  r.details["normals"] = o.estimate_normals ? "estimated"
                         : !normals.empty() ? normals
                         : own              ? "reference file"
                                            : "none";
  r.warnings.insert(r.warnings.begin(), reading.begin(), reading.end());
  return r;
}

/// psnr on inputs read as run_metric reads them: two meshes (mmetric's grid), two clouds by
/// mmetric's conventions, or two clouds by pc_error's.
MetricResult run_on_inputs(const GridSampler& grid_sampler, const Input& ref, const Input& dist,
                           MeshPsnrOptions o, const OptionValues& v) {
  const std::string normals = v.at("normals").get<std::string>();
  const std::string d2_normals = v.at("d2_normals").get<std::string>();
  const std::string conventions = v.at("conventions").get<std::string>();
  if (ref.is_mesh() != dist.is_mesh()) {
    const Input& mesh = ref.is_mesh() ? ref : dist;
    throw FormatError("psnr: " + mesh.name() +
                      " is a mesh and the other input a cloud; psnr "
                      "compares two meshes (sampled on one grid) or two clouds: sample the "
                      "mesh first (qm3d sample --mode grid)");
  }
  if (ref.is_mesh() && dist.is_mesh()) {
    if (conventions == "pc_error") {
      throw std::invalid_argument(
          "conventions: two meshes are sampled and compared as mmetric "
          "does; pc_error applies to clouds");
    }
    if (!normals.empty()) {
      throw std::invalid_argument(
          "normals: two meshes are compared on their samples' face "
          "normals; --normals applies to clouds");
    }
    o.grid_size = v.at("grid_size").get<int>();
    o.d2_normals = d2_normals == "transferred" ? D2Normals::kTransferred : D2Normals::kOwn;
    o.bilinear = v.at("bilinear").get<bool>();
    return compute_mesh_psnr(ref, dist, grid_sampler, o);
  }
  if (conventions == "mmetric") {
    if (!normals.empty()) {
      throw std::invalid_argument(
          "normals: with conventions mmetric each cloud's own normals "
          "are used (as mm compare); --normals applies to pc_error's");
    }
    MetricResult r = compute_psnr_mmetric(
        ref.cloud(), ref.cloud_normals(), dist.cloud(), dist.cloud_normals(), o,
        d2_normals == "transferred" ? D2Normals::kTransferred : D2Normals::kOwn, ref.name(),
        dist.name());
    r.details["normals"] = ref.cloud_normals().empty() ? "none" : "each file's own";
    return r;
  }
  if (d2_normals == "own") {
    throw std::invalid_argument(
        "d2_normals: own applies to two meshes, or to two clouds with "
        "--conventions mmetric; pc_error transfers the reference's "
        "normals");
  }
  const ReferenceNormals given = normals.empty() || o.estimate_normals
                                     ? ReferenceNormals{ref.cloud_normals(), {}, {}}
                                     : normals_file(normals);
  MetricResult r = compute_psnr(ref.cloud(), given, dist.cloud(), o, ref.name(), dist.name());
  r.details["normals"] = o.estimate_normals      ? "estimated"
                         : !normals.empty()      ? normals
                         : given.normals.empty() ? "none"
                                                 : "reference file";
  return r;
}

}  // namespace

MetricSpec psnr_spec(GridSampler grid_sampler) {
  MetricSpec s;
  s.name = "psnr";
  s.title = "PSNR";
  s.reproduces =
      "MPEG pc_error 0.14.2 (MPEGGroup/mpeg-pcc-dmetric @ bd6df59); meshes: MPEG mmetric 1.1.7 "
      "(MPEGGroup/mpeg-pcc-mmetric @ 5faa660)";
  s.summary =
      "MPEG pc_error's D1 (point-to-point) and D2 (point-to-plane) PSNR, Hausdorff and colour "
      "PSNR between two point clouds (pc_error 0.14.2's values), or between two meshes sampled "
      "on one grid as MPEG mmetric does (mm sample --mode grid + compare --mode pcc, the "
      "V-DMC CTC); score = symmetric D1 PSNR, dB";
  s.higher_is_better = true;
  // What compare and batch run it on; `qm3d psnr` itself also takes two meshes (the run below).
  s.applies_to = AppliesTo::kClouds;
  s.reads = Input::Kind::kCloud;
  s.reads_two_meshes_as_meshes = true;
  s.two_meshes_scored_on_samples = true;
  s.default_direction = Direction::kSymmetric;
  s.direction_help =
      "symmetric: both passes, each value the worse of the two (pc_error's \"Final\"); "
      "ref-to-dist: the reference's points matched on the distorted cloud (pc_error's A->B, -s); "
      "dist-to-ref: the distorted cloud's points matched on the reference (B->A)";
  s.symmetric_rule = "worse of the two";
  s.per_element_on_input = true;
  s.value_names = psnr_value_names();
  for (const std::string& n : s.value_names) {
    if (n.size() > 5 && n.compare(n.size() - 5, 5, "_psnr") == 0)
      s.quality_value_names.push_back(n);
  }
  s.options = {
      {"peak",
       "Peak p of the geometry PSNRs, 10 log10(3 p^2 / mse) (pc_error -r, e.g. 1023 for 10-bit "
       "voxels); 0 = pc_error's default: the largest nearest-neighbour distance in the "
       "reference (echoed in the output)",
       0.0,
       {},
       0,
       3.4e38},
      {"color_space",
       "Colour space of the colour values: ycbcr (BT.709, peak 1; pc_error --mseSpace 1), rgb "
       "(peak 255; 0), ycocg (YCoCg-R, peaks 255/511/511; 8)",
       "ycbcr",
       {"ycbcr", "rgb", "ycocg"}},
      {"drop_duplicates",
       "Points of equal coordinates in a cloud: 0 keep, 1 keep the first, 2 merge them into one "
       "with their mean colour (pc_error --dropdups)",
       2,
       {},
       0,
       2},
      {"neighbours",
       "Colour of several nearest neighbours at the same distance: 1 their mean, 2 their mean "
       "weighted by the duplicates each merged (pc_error --neighborsProc)",
       1,
       {},
       1,
       2},
      {"average_normals",
       "D2 over every nearest neighbour at the same distance and normals transferred by "
       "averaging (pc_error --averageNormals=1); false: the first neighbour only",
       true},
      {"normals",
       "Normals of D2: empty = the reference file's nx, ny, nz; FILE = a PLY of the reference's "
       "points with normals (pc_error -n); estimate = computed as "
       "shared/tools/add_pca_normals.py does (k = 12, outward from the centroid)",
       ""},
      {"grid_size",
       "Two meshes: grid nodes along the longest side of the union of their vertex boxes, "
       "both sampled on that grid (mm sample --mode grid --gridSize; the CTC's 1024)",
       1024,
       {},
       2,
       1000000},
      {"d2_normals",
       "Normals D2 projects on in the pass reference -> distorted: auto = own for two meshes "
       "(the distorted mesh's sampled face normals, mmetric's default), transferred for clouds "
       "(the reference's normals transferred to the distorted points, pc_error; mmetric "
       "--normalCalcModificationEnable=false)",
       "auto",
       {"auto", "own", "transferred"}},
      {"conventions",
       "Whose rules: auto = pc_error's for two clouds, mmetric's for two meshes; mmetric = "
       "mmetric's compare --mode pcc also for two clouds (normals of merged duplicates averaged, "
       "D2 of the pass reference -> distorted on the distorted cloud's own normals, ties 1e-20, "
       "peak = the reference's box diagonal); pc_error = pc_error's (two clouds only)",
       "auto",
       {"auto", "pc_error", "mmetric"}},
      {"bilinear",
       "Two meshes: texture colours of a textured OBJ looked up bilinearly (mmetric --bilinear) "
       "instead of at the nearest texel",
       false},
      {"no_hausdorff", "Leave out the Hausdorff values (pc_error without -d 1)", false},
      {"no_color", "Geometry only: leave out the colour values (pc_error without -c 1)", false},
  };
  // psnr reads its inputs itself (read_own, read_inputs): two clouds without the general
  // reader's double-precision copy.
  s.reads_files = true;
  s.run = [grid_sampler](const MetricSpec&, const Input& ref, const Input& dist,
                         const RunOptions& run, const OptionValues& v) {
    const MeshPsnrOptions o = psnr_options(run, v);
    if (std::optional<MetricResult> r = run_on_own_reads(ref, dist, o, v)) return *r;
    const bool two_meshes = ref.is_mesh() && dist.is_mesh();
    const std::vector<std::string> reading =
        read_inputs(ref, dist, two_meshes ? Input::Kind::kMesh : Input::Kind::kCloud, run.threads);
    MetricResult r = run_on_inputs(grid_sampler, ref, dist, o, v);
    r.warnings.insert(r.warnings.begin(), reading.begin(), reading.end());
    return r;
  };
  return s;
}

}  // namespace qm3d::pointcloud
