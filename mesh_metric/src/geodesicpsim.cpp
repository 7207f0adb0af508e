// GeodesicPSIM (qm3d/mesh/geodesicpsim.h): keypoints, per-patch similarities and their pooling
// (SPEC-GEODESICPSIM steps 5, 9, 10). Reference: Qi-Yangsjtu/GeodesicPSIM @ 3e06453 (no licence;
// implemented from the paper, arXiv:2308.04928, and the SPEC; nothing copied).
#include "qm3d/mesh/geodesicpsim.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "geodesicpsim_internal.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/progress.h"
#include "qm3d/mesh/texture.h"

namespace qm3d::mesh {
namespace {

using gpsim::GpMesh;
using gpsim::GpTexture;
using gpsim::KeypointValues;

/// The reference's stabiliser of every similarity (2ab + t) / (a² + b² + t).
constexpr double kSimilarityEps = 1e-6;
/// Patch size limit: 0.001 x 0.5 x the largest side of the reference's box (the reference's
/// PatchRediux).
constexpr double kPatchRadiusPerBox = 0.001;
constexpr double kPatchRadiusHalf = 0.5;
/// Weights of Y, U, V in every colour similarity (6:1:1).
constexpr double kLumaWeight = 6, kChannelWeightSum = 8;
/// The reference's keypoint loop: 11 blocks of floor(N / 10) keypoints when N >= 10 (the
/// keypoints after them are never computed: they count as skipped).
constexpr int kBlockDivisor = 10;

double similarity(double a, double b) {
  return (2 * a * b + kSimilarityEps) / (a * a + b * b + kSimilarityEps);
}
// The smoothness similarity takes |2ab|.
double abs_similarity(double a, double b) {
  return (std::fabs(2 * a * b) + kSimilarityEps) / (a * a + b * b + kSimilarityEps);
}
double yuv_mix(double y, double u, double v) {
  return (kLumaWeight * y + u + v) / kChannelWeightSum;
}

struct LoadedMesh {
  GpMesh mesh;
  std::filesystem::path texture_file;  // the MTL's map_Kd
  std::shared_ptr<const GpTexture> texture;
};

LoadedMesh load(const std::filesystem::path& path) {
  LoadedMesh m;
  {
    const std::string text = read_file_bytes(path);
    m.mesh = gpsim::read_obj_as_reference(text, path.string());
    m.texture_file = obj_texture_file(text, path);
  }
  m.mesh = gpsim::clean_mesh(std::move(m.mesh));
  if (m.mesh.f.empty()) throw NumericError(path.string() + ": no face left after cleaning");
  return m;
}

gpsim::PatchSource patch_source(const LoadedMesh& m, gpsim::NearestVertex& nearest) {
  gpsim::PatchSource s;
  s.mesh = &m.mesh;
  s.texture = m.texture.get();
  s.nearest = &nearest;
  s.face_offsets.assign(m.mesh.v.size() + 1, 0);
  for (const auto& f : m.mesh.f) {
    for (int v : f) ++s.face_offsets[v + 1];
  }
  for (std::size_t i = 1; i < s.face_offsets.size(); ++i)
    s.face_offsets[i] += s.face_offsets[i - 1];
  s.faces.resize(s.face_offsets.back());
  std::vector<int> fill(s.face_offsets.begin(), s.face_offsets.end() - 1);
  for (std::size_t f = 0; f < m.mesh.f.size(); ++f) {
    const auto& t = m.mesh.f[f];
    for (int k = 0; k < 3; ++k) {
      // A vertex appears once per face (repeated indices were cleaned away).
      s.faces[fill[t[k]]++] = static_cast<int>(f);
    }
  }
  return s;
}

double largest_box_side(const std::vector<gpsim::P3>& v) {
  double side = 0;
  for (int d = 0; d < 3; ++d) {
    double lo = v[0][d], hi = v[0][d];
    for (const auto& p : v) {
      lo = std::min(lo, p[d]);
      hi = std::max(hi, p[d]);
    }
    side = std::max(side, hi - lo);
  }
  return side;
}

// The per-patch similarities of a computed patch (SPEC step 9).
void patch_similarities(const KeypointValues& v, GeodesicPsimKeypoint& k) {
  std::array<double, 3> s;
  for (int c = 0; c < 3; ++c) {
    s[c] = abs_similarity(v.ref_smooth[c] / v.ref_npix, v.dis_smooth[c] / v.dis_npix);
  }
  k.pcs = yuv_mix(s[0], s[1], s[2]);
  k.dmc = similarity(v.ref_cur, v.dis_cur);
  // A negative curvature similarity is recomputed on both values raised by their difference.
  if (!std::isnan(k.dmc) && k.dmc < 0) {
    const double shift = std::fabs(v.ref_cur - v.dis_cur);
    k.dmc = similarity(v.ref_cur + shift, v.dis_cur + shift);
  }
  const auto &a = v.ref_stats, &b = v.dis_stats;
  k.lm = similarity(a.lm, b.lm);
  k.lvar = similarity(a.lvar, b.lvar);
  k.c1m = similarity(a.c1m, b.c1m);
  k.c1var = similarity(a.c1var, b.c1var);
  k.c2m = similarity(a.c2m, b.c2m);
  k.c2var = similarity(a.c2var, b.c2var);
}

// Sums of one flag's patches, in keypoint order.
struct FlagSums {
  double pcs = 0, dmc = 0, lm = 0, lvar = 0, c1m = 0, c1var = 0, c2m = 0, c2var = 0;
  int count = 0, count_dmc = 0;
  void add(const GeodesicPsimKeypoint& k) {
    ++count;
    pcs += k.pcs;
    if (!std::isnan(k.dmc)) {  // a NaN curvature similarity leaves the dmc mean only
      dmc += k.dmc;
      ++count_dmc;
    }
    lm += k.lm;
    lvar += k.lvar;
    c1m += k.c1m;
    c1var += k.c1var;
    c2m += k.c2m;
    c2var += k.c2var;
  }
  double pca() const { return yuv_mix(lm / count, c1m / count, c2m / count); }
  double pcv() const { return yuv_mix(lvar / count, c1var / count, c2var / count); }
};

// Means over flag-1 patches, mixed with flag-2 patches' as (X1 + r X2) / (1 + r), r = n2 / (n1 +
// n2); flag-3 patches' means only when there is no flag-1/2 patch (SPEC step 10). The
// reference's partial states are kept: without a flag-1 dmc the flag-1 sums stay undivided.
void pool(const FlagSums& f1, const FlagSums& f2, const FlagSums& f3, GeodesicPsimResult& r) {
  if (f1.count + f2.count == 0) {
    r.pcs = f3.pcs / f3.count;
    r.dmc = f3.dmc / f3.count_dmc;
    r.pca = f3.pca();
    r.pcv = f3.pcv();
  } else {
    double one = 0;
    r.pcs = f1.pcs;
    r.dmc = f1.dmc;
    if (f1.count > 0 && f1.count_dmc > 0) {
      one = 1;
      r.pcs = f1.pcs / f1.count;
      r.dmc = f1.dmc / f1.count_dmc;
      r.pca = f1.pca();
      r.pcv = f1.pcv();
    }
    if (f2.count > 0 && f2.count_dmc > 0) {
      const double ratio = double(f2.count) / (f1.count + f2.count);
      r.pcs = (r.pcs + ratio * (f2.pcs / f2.count)) / (one + ratio);
      r.dmc = (r.dmc + ratio * (f2.dmc / f2.count_dmc)) / (one + ratio);
      r.pcv = (r.pcv + ratio * f2.pcv()) / (one + ratio);
      r.pca = (r.pca + ratio * f2.pca()) / (one + ratio);
    }
  }
  r.score = (r.pcs + r.dmc + r.pcv + r.pca) / 4;
}

// `pair` names both files in messages.
void pool_keypoints(const std::vector<KeypointValues>& values, const std::string& pair,
                    GeodesicPsimResult& r) {
  const bool any12 = std::any_of(values.begin(), values.end(), [](const KeypointValues& v) {
    return v.flag == 1 || v.flag == 2;
  });
  FlagSums sums[4];
  for (std::size_t k = 0; k < values.size(); ++k) {
    const KeypointValues& v = values[k];
    GeodesicPsimKeypoint& kp = r.keypoints[k];
    kp.flag = v.flag;
    kp.center_shift = v.center_shift;
    kp.patch_size = v.patch_size;
    kp.ref_texels = v.ref_npix;
    kp.dis_texels = v.dis_npix;
    kp.ref_smoothness = v.ref_smooth;
    kp.dis_smoothness = v.dis_smooth;
    kp.ref_curvature = v.ref_cur;
    kp.dis_curvature = v.dis_cur;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    kp.pcs = kp.dmc = kp.lm = kp.lvar = kp.c1m = kp.c1var = kp.c2m = kp.c2var = nan;
    if (v.flag == 0) {
      ++r.skipped;
      continue;
    }
    (v.flag == 1 ? r.flag1 : v.flag == 2 ? r.flag2 : r.flag3)++;
    if (v.flag == 3 && any12) continue;
    patch_similarities(v, kp);
    kp.pooled = true;
    sums[v.flag].add(kp);
  }
  r.effective_patches = any12 ? r.flag1 + r.flag2 : r.flag3;
  if (r.effective_patches == 0) {
    throw NumericError(pair + ": no keypoint has a patch of more than 3 vertices in both meshes");
  }
  pool(sums[1], sums[2], sums[3], r);
}

std::vector<KeypointValues> all_keypoint_values(const LoadedMesh& ref, const LoadedMesh& dis,
                                                const std::vector<gpsim::P3>& keypoints,
                                                double threshold, int threads) {
  gpsim::NearestVertex ref_nearest(ref.mesh.v), dis_nearest(dis.mesh.v);
  const gpsim::PatchSource rs = patch_source(ref, ref_nearest), ds = patch_source(dis, dis_nearest);
  const int n = static_cast<int>(keypoints.size());
  const int computed =
      n < kBlockDivisor ? n : std::min(n, (kBlockDivisor + 1) * (n / kBlockDivisor));
  std::vector<KeypointValues> values(keypoints.size());
#pragma omp parallel for schedule(dynamic, 16) num_threads(threads)
  for (int k = 0; k < computed; ++k) {
    values[k] = gpsim::keypoint_values(rs, ds, keypoints[k], threshold);
  }
  return values;
}

// The per-keypoint values of the patches that entered the score, at their keypoints.
void keypoint_values_of(const GeodesicPsimResult& g, DirectionResult& d) {
  std::vector<double> flag, pcs, dmc, pca, pcv;
  for (const GeodesicPsimKeypoint& k : g.keypoints) {
    if (!k.pooled) continue;
    d.element_positions.push_back(k.position);
    d.per_element.push_back(k.local_score());
    flag.push_back(k.flag);
    pcs.push_back(k.pcs);
    dmc.push_back(k.dmc);
    pca.push_back(yuv_mix(k.lm, k.c1m, k.c2m));
    pcv.push_back(yuv_mix(k.lvar, k.c1var, k.c2var));
  }
  d.per_element_values = {{"flag", flag}, {"pcs", pcs}, {"dmc", dmc}, {"pca", pca}, {"pcv", pcv}};
}

void check_textured_obj(const Input& in) {
  if (in.path().empty() || in.format() != FileFormat::kObj) {
    throw FormatError(in.name() +
                      ": geodesicpsim reads textured OBJ files (OBJ + MTL + texture image)");
  }
}

MetricResult run_geodesicpsim(const MetricSpec&, const Input& ref, const Input& dist,
                              const RunOptions& run, const OptionValues& v) {
  check_textured_obj(ref);
  check_textured_obj(dist);
  GeodesicPsimOptions o;
  static_cast<RunOptions&>(o) = run;
  o.keypoints = v.at("keypoints").get<int>();
  const std::filesystem::path ref_path = ref.path(), dist_path = dist.path();
  if (run.inputs_done) run.inputs_done();  // nothing of the inputs is used: their files are read
  const GeodesicPsimResult g = compute_geodesicpsim(ref_path, dist_path, o);
  MetricResult r;
  r.metric = "geodesicpsim";
  r.values = {{"pcs", g.pcs}, {"dmc", g.dmc}, {"pca", g.pca}, {"pcv", g.pcv}};
  DirectionResult d;
  d.score = g.score;
  d.values = r.values;
  if (run.per_element) keypoint_values_of(g, d);
  r.ref_to_dist = std::move(d);
  r.score = g.score;
  r.details = {{"keypoints", g.keypoints_used},
               {"effective_patches", g.effective_patches},
               {"flag1", g.flag1},
               {"flag2", g.flag2},
               {"flag3", g.flag3},
               {"skipped", g.skipped},
               {"subdivided", g.subdivided}};
  r.text_note = std::to_string(g.effective_patches) + " of " + std::to_string(g.keypoints_used) +
                " keypoint patches pooled";
  r.provenance.options = v;
  return r;
}

}  // namespace

MetricSpec geodesicpsim_spec() {
  MetricSpec s;
  s.name = "geodesicpsim";
  s.title = "GeodesicPSIM";
  s.reproduces = "Qi-Yangsjtu/GeodesicPSIM @ 3e06453";
  s.summary =
      "Textured-mesh quality by geodesic patch similarity around farthest-point keypoints (colour "
      "smoothness, mean curvature, texel mean and variance); two textured OBJ files; score in "
      "[0, 1], 1 = identical";
  s.higher_is_better = true;
  s.applies_to = AppliesTo::kMeshes;
  s.reads = Input::Kind::kMesh;
  s.reads_files = true;  // the OBJ and its texture as the reference reads them (float32)
  s.in_compare = false;  // needs textured OBJ files; asked for by name
  s.default_direction = Direction::kRefToDist;
  s.direction_help = "keypoints on the reference, patches in both meshes (one direction)";
  s.symmetric_rule = "the one direction (keypoints on the reference)";
  s.per_element_on_input = false;  // one value per keypoint (a cleaned reference vertex)
  s.per_element_positions = true;
  s.value_names = {"pcs", "dmc", "pca", "pcv"};
  s.quality_value_names = s.value_names;
  s.options = {{"keypoints",
                "Farthest-point keypoints on the reference (the reference tool's --N); at most "
                "the reference's vertex count",
                5000,
                {},
                1,
                1e9}};
  s.run = run_geodesicpsim;
  return s;
}

double GeodesicPsimKeypoint::local_score() const {
  if (!pooled) return std::numeric_limits<double>::quiet_NaN();
  return (pcs + dmc + yuv_mix(lm, c1m, c2m) + yuv_mix(lvar, c1var, c2var)) / 4;
}

GeodesicPsimResult compute_geodesicpsim(const std::filesystem::path& reference_obj,
                                        const std::filesystem::path& distorted_obj,
                                        const GeodesicPsimOptions& options) {
  if (options.keypoints < 1) throw std::invalid_argument("keypoints: must be at least 1");
  ProgressSteps progress(options.progress, 5);
  progress.begin("reading");
  LoadedMesh ref = load(reference_obj);
  LoadedMesh dis = load(distorted_obj);
  // One copy of a texture both meshes name (a geometry-only distortion).
  ref.texture = std::make_shared<const GpTexture>(gpsim::read_texture_8bit(ref.texture_file));
  std::error_code same_error;
  dis.texture = std::filesystem::equivalent(ref.texture_file, dis.texture_file, same_error)
                    ? ref.texture
                    : std::make_shared<const GpTexture>(gpsim::read_texture_8bit(dis.texture_file));
  GeodesicPsimResult r;
  progress.begin("equalising face counts");
  const gpsim::Subdivided sub = gpsim::equalise_face_counts(ref.mesh, dis.mesh);
  r.subdivided = sub == gpsim::Subdivided::kReference   ? "reference"
                 : sub == gpsim::Subdivided::kDistorted ? "distorted"
                                                        : "none";
  r.keypoints_used = std::min<int>(options.keypoints, static_cast<int>(ref.mesh.v.size()));
  progress.begin("keypoints");
  const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();
  const std::vector<gpsim::P3> keypoints =
      gpsim::farthest_points(ref.mesh.v, r.keypoints_used, threads);
  const double threshold = kPatchRadiusPerBox * largest_box_side(ref.mesh.v) * kPatchRadiusHalf;
  progress.begin("patches", 2);
  const auto values = all_keypoint_values(ref, dis, keypoints, threshold, threads);
  r.keypoints.resize(keypoints.size());
  for (std::size_t k = 0; k < keypoints.size(); ++k) r.keypoints[k].position = keypoints[k];
  pool_keypoints(values, reference_obj.string() + " vs " + distorted_obj.string(), r);
  progress.finish();
  return r;
}

}  // namespace qm3d::mesh
