// The registry metric `icid` (qm3d/render/icid.h icid_spec): both objects rendered as ibsm
// renders them (ibsm.h: frame, layouts, lighting, splats), iCID of each view pair, the views'
// mean as the score — the CMDM report's image-metric protocol (18 views, arithmetic mean).
#include <omp.h>

#include <chrono>
#include <exception>

#include "qm3d/common/error.h"
#include "qm3d/common/version.h"
#include "qm3d/render/ibsm.h"
#include "qm3d/render/icid.h"

namespace qm3d::render {
namespace {

/// A view as its PNG holds it (top row first; raster.h stores the bottom row first), alpha
/// dropped: where nothing is drawn the background's (0, 0, 0).
RgbImage rgb_of(const View& v) {
  RgbImage out{v.width, v.height, {}};
  out.rgb.resize(static_cast<std::size_t>(v.width) * v.height * 3);
  for (int y = 0; y < v.height; ++y) {
    const std::size_t src_row = static_cast<std::size_t>(v.height - 1 - y) * v.width;
    const std::size_t dst_row = static_cast<std::size_t>(y) * v.width;
    for (int x = 0; x < v.width; ++x) {
      for (int c = 0; c < 3; ++c) out.rgb[(dst_row + x) * 3 + c] = v.rgba[(src_row + x) * 4 + c];
    }
  }
  return out;
}

int thread_count(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

/// iCID of every view pair, the pairs in parallel (each on one thread: the same values as any
/// other split, icid.h), each written to its own slot.
std::vector<IcidResult> icid_of_views(const std::vector<View>& va, const std::vector<View>& vb,
                                      const Lab2000hlTable& table, IcidOptions o, int threads) {
  o.threads = 1;
  std::vector<IcidResult> out(va.size());
  std::vector<std::exception_ptr> errors(va.size());
  const int n = static_cast<int>(va.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(thread_count(threads))
  for (int i = 0; i < n; ++i) {
    try {
      out[i] = icid(rgb_of(va[i]), rgb_of(vb[i]), table, o);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  }
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  return out;
}

IcidOptions icid_options(const OptionValues& v, int threads) {
  IcidOptions o;
  o.intent = icid_intent(v.at("intent").get<std::string>());
  o.iam = !v.at("no_iam").get<bool>();
  o.omit_maps67 = v.at("omit_maps67").get<bool>();
  o.downsampling = !v.at("no_downsampling").get<bool>();
  o.threads = threads;
  return o;
}

nlohmann::json view_json(const Float3& direction, const IcidResult& r) {
  nlohmann::json j;
  j["direction"] = {direction[0], direction[1], direction[2]};
  j["icid"] = r.icid;
  for (int k = 0; k < 7; ++k) j[icid_map_names()[k]] = r.maps[k];
  return j;
}

/// The mean over the views of the score and of each map (in view order).
NamedValues mean_values(const std::vector<IcidResult>& views) {
  double icid_sum = 0;
  std::array<double, 7> map_sums{};
  for (const IcidResult& r : views) {
    icid_sum += r.icid;
    for (int k = 0; k < 7; ++k) map_sums[k] += r.maps[k];
  }
  const double n = static_cast<double>(views.size());
  NamedValues values{{"icid", icid_sum / n}};
  for (int k = 0; k < 7; ++k) values.emplace_back(icid_map_names()[k], map_sums[k] / n);
  return values;
}

MetricResult run_icid(const MetricSpec&, const Input& ref, const Input& dist, const RunOptions& run,
                      const OptionValues& v) {
  const auto start = std::chrono::steady_clock::now();
  OptionValues render_values = v;
  render_values["no_ssim"] = true;
  render_values["save_views"] = "";
  const IbsmOptions o = ibsm_options(render_values, run);
  const std::vector<Float3> dirs = view_directions(o);
  const auto table = Lab2000hlTable::shared(icid_table_dir(run.data_dir));
  const RenderModel a = model_of(ref, o.splats), b = model_of(dist, o.splats);
  if (run.inputs_done) run.inputs_done();
  const Frame frame = frame_of(a, b);
  const RasterOptions ro{o.resolution, o.culling, o.lighting};
  const std::vector<View> va = render_views(a, frame, dirs, ro, run.threads);
  const std::vector<View> vb = render_views(b, frame, dirs, ro, run.threads);
  const IcidOptions io = icid_options(v, run.threads);
  const std::vector<IcidResult> views = icid_of_views(va, vb, *table, io, run.threads);
  nlohmann::json per_view = nlohmann::json::array();
  for (std::size_t i = 0; i < dirs.size(); ++i) per_view.push_back(view_json(dirs[i], views[i]));
  MetricResult r;
  r.metric = "icid";
  DirectionResult d;
  d.values = mean_values(views);
  d.score = d.values.front().second;
  r.values = d.values;
  r.score = d.score;
  r.dist_to_ref = d;
  r.ref_to_dist = d;
  for (const Input* in : {&ref, &dist}) {
    if (!in->is_mesh()) continue;
    r.warnings.insert(r.warnings.end(), in->mesh().warnings.begin(), in->mesh().warnings.end());
  }
  r.details["render"] = {{"layout", o.layout == ViewLayout::kCmdm18 ? "cmdm18" : "fibonacci"},
                         {"resolution", o.resolution},
                         {"lighting", o.lighting == Lighting::kHeadlight ? "headlight" : "none"}};
  r.details["views"] = per_view;
  r.text_note = "mean over " + std::to_string(dirs.size()) + " views";
  r.provenance.version = kVersion;
  r.provenance.reference = ref.name();
  r.provenance.distorted = dist.name();
  r.provenance.options = v;
  r.provenance.seconds = seconds_since(start);
  return r;
}

std::vector<OptionSpec> icid_metric_options() {
  return {
      {"layout",
       "Where the cameras are: cmdm18 = the CMDM report's 18 directions (6 axes + 12 plane "
       "diagonals); fibonacci = --views directions on mmetric's Fibonacci sphere",
       "cmdm18",
       {"fibonacci", "cmdm18"}},
      {"views", "Views on a Fibonacci sphere (fibonacci layout)", 16, {}, 2, 4096},
      {"resolution",
       "Width = height of each view, pixels (iCID downsamples views above 383)",
       256,
       {},
       16,
       16384},
      {"rotation", "Rotation of the Fibonacci views: polar angle, azimuth, magnitude (degrees)",
       nlohmann::json::array({0.0, 0.0, 0.0})},
      {"no_culling", "Draw back faces too", false},
      {"lighting",
       "headlight = meshes shaded by a light at the camera (as the reference table's views); "
       "none = the colours themselves",
       "headlight",
       {"none", "headlight"}},
      {"splat_size",
       "Size of a point cloud's splats, world units; 0 = 6 x the median spacing",
       0.0,
       {},
       0,
       1e300},
      {"splat_shape", "Shape of a point cloud's splats", "disc", {"disc", "square"}},
      {"intent",
       "iCID's prediction intent",
       "perceptual",
       {"perceptual", "hue-preserving", "chromatic"}},
      {"no_iam", "Leave out the image-appearance model (iCID IAM = 'NONE')", false},
      {"omit_maps67", "Leave out the chroma contrast and structure maps (Omit_Maps67)", false},
      {"no_downsampling", "Never downsample the views (Downsampling = false)", false},
  };
}

}  // namespace

MetricSpec icid_spec() {
  MetricSpec s;
  s.name = "icid";
  s.title = "iCID";
  s.reproduces =
      "iCID v1.00 (Preiss, Fernandes, Urban 2014) MATLAB code, Netflix/vmaf @ f85a853 "
      "matlab/cid_icid/iCID/iCID_Metric";
  s.summary =
      "Colour-image difference (iCID) of rendered views, the CMDM report's protocol (18 views, "
      "mean); meshes and point clouds; score = mean iCID (0 = identical)";
  s.higher_is_better = false;
  s.applies_to = AppliesTo::kBoth;
  s.reads = Input::Kind::kCloud;
  s.reads_two_meshes_as_meshes = true;
  s.reads_each_as_is = true;
  s.in_compare = false;  // rendering and FFT filtering of every view: asked for by name
  s.default_direction = Direction::kSymmetric;
  s.direction_help = "one comparison of the two images of each view (both directions are the same)";
  s.symmetric_rule = "the same image comparison";
  s.per_element_on_input = false;
  s.value_names = {"icid"};
  for (const std::string& n : icid_map_names()) s.value_names.push_back(n);
  s.options = icid_metric_options();
  s.run = run_icid;
  return s;
}

}  // namespace qm3d::render
