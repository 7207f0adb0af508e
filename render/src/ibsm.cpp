// IBSM (qm3d/render/ibsm.h). The per-pixel rules are mmetric 1.1.7's (MPEGGroup/mpeg-pcc-mmetric
// @ 5faa660, source/lib/source/mmCompare.cpp `Compare::ibsm`; colour conversion mmColor.h
// rgbToYuvBt709_256), reimplemented: float YUV, double squared differences, sums over every
// view, then MSE = sum / matched pixels.
#include "qm3d/render/ibsm.h"

#include <omp.h>
#include <stb/stb_image_write.h>

#include <array>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <memory>
#include <ostream>
#include <stdexcept>

#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/grid_samples.h"
#include "qm3d/common/version.h"
#include "qm3d/mesh/texture.h"
#include "qm3d/render/icid.h"
#include "qm3d/render/image_quality.h"
#include "raster_bands.h"
#include "ssim_stream.h"

namespace qm3d::render {

const std::vector<std::string>& ibsm_value_names() {
  // clang-format off
  static const std::vector<std::string> names = {
      "r_mse",   "g_mse",   "b_mse",   "rgb_mse", "y_mse",    "u_mse",    "v_mse",
      "yuv_mse", "geo_mse", "r_psnr",  "g_psnr",  "b_psnr",   "rgb_psnr", "y_psnr",
      "u_psnr",  "v_psnr",  "yuv_psnr", "geo_psnr", "unmatched_pixel_percentage", "ssim",
      "ms_ssim"};
  // clang-format on
  return names;
}

namespace {

/// mmColor.h rgbToYuvBt709_256's Y, in float as mmetric.
float luma_of(float r, float g, float b) { return 0.2126F * r + 0.7152F * g + 0.0722F * b; }

/// mmColor.h rgbToYuvBt709_256, in float as mmetric.
Float3 yuv_of(float r, float g, float b) {
  return {luma_of(r, g, b), -0.1146F * r - 0.3854F * g + 0.5000F * b + 128.0F,
          0.5000F * r - 0.4542F * g - 0.0458F * b + 128.0F};
}

/// A view's error sums while a row is compared (locals: the sums run in registers, each the
/// same running sum as the view's, in pixel order).
struct ErrorSums {
  double rgb[3], yuv[3], depth;
  std::size_t matched, unmatched;
  explicit ErrorSums(const IbsmView& v)
      : rgb{v.rgb_sse[0], v.rgb_sse[1], v.rgb_sse[2]},
        yuv{v.yuv_sse[0], v.yuv_sse[1], v.yuv_sse[2]},
        depth(v.depth_sse),
        matched(v.matched),
        unmatched(v.unmatched) {}
  void store(IbsmView& v) const {
    for (int c = 0; c < 3; ++c) v.rgb_sse[c] = rgb[c], v.yuv_sse[c] = yuv[c];
    v.depth_sse = depth;
    v.matched = matched;
    v.unmatched = unmatched;
  }
  /// Squared errors of a pixel both views cover (mmetric's steps A, B).
  void add(const std::uint8_t* a, float depth_a, const std::uint8_t* b, float depth_b,
           float depth_range) {
    const float ra = a[0], ga = a[1], ba = a[2];
    const float rb = b[0], gb = b[1], bb = b[2];
    const Float3 rgb_a{ra, ga, ba}, rgb_b{rb, gb, bb};
    const Float3 yuv_a = yuv_of(ra, ga, ba), yuv_b = yuv_of(rb, gb, bb);
    for (int c = 0; c < 3; ++c) {
      const double d_rgb = static_cast<double>(rgb_a[c]) - static_cast<double>(rgb_b[c]);
      const double d_yuv = static_cast<double>(yuv_a[c]) - static_cast<double>(yuv_b[c]);
      rgb[c] += d_rgb * d_rgb;
      yuv[c] += d_yuv * d_yuv;
    }
    const double d =
        (static_cast<double>(depth_a) - static_cast<double>(depth_b)) * 255.0 / depth_range;
    depth += d * d;
  }
};

/// Rows per band: both views' bands (8 bytes a pixel each) stay in the cache.
constexpr int kBandRows = 64;

/// One thread's view comparison: both objects drawn band by band into the same buffers, each
/// band's errors summed and its rows (luma, mask) fed to the streaming SSIM, so that a thread
/// holds a few bands rather than two views.
class ViewScorer {
 public:
  IbsmView score(const RenderModel& ref, const RenderModel& dist, const Frame& frame,
                 const Float3& direction, const IbsmOptions& o) {
    const RasterOptions ro{o.resolution, o.culling, o.lighting};
    ref_.prepare(ref, frame, direction, ro, kBandRows);
    dist_.prepare(dist, frame, direction, ro, kBandRows);
    const int w = ref_.width();
    const std::size_t band_pixels = static_cast<std::size_t>(w) * kBandRows;
    for (auto* v : {&rgba_a_, &rgba_b_}) v->resize(4 * band_pixels);
    for (auto* v : {&depth_a_, &depth_b_}) v->resize(band_pixels);
    for (auto* v : {&luma_a_, &luma_b_}) v->assign(static_cast<std::size_t>(w), 0.0);
    mask_.assign(static_cast<std::size_t>(w), 0);
    if (o.image_quality) ssim_.begin(w, ref_.height());
    IbsmView out;
    out.direction = direction;
    out.ssim = out.ms_ssim = std::numeric_limits<double>::quiet_NaN();
    drawn_a_ = drawn_b_ = 0;
    for (int band = 0; band < ref_.bands(); ++band) {
      ref_.draw(band, rgba_a_.data(), depth_a_.data());
      dist_.draw(band, rgba_b_.data(), depth_b_.data());
      for (int y = 0; y < ref_.band_rows(band); ++y) {
        // Columns outside both views' drawn spans are empty in both: luma 0, not in the mask.
        const std::array<int, 2> span_a = ref_.drawn_columns(y), span_b = dist_.drawn_columns(y);
        const int x0 = std::min(span_a[0], span_b[0]), x1 = std::max(span_a[1], span_b[1]);
        const std::size_t r = static_cast<std::size_t>(y) * static_cast<std::size_t>(w);
        compare_row(&rgba_a_[4 * r], &depth_a_[r], &rgba_b_[4 * r], &depth_b_[r], x0, x1,
                    dist_.depth_range(), out);
        if (o.image_quality) ssim_.push_row(luma_a_.data(), luma_b_.data(), mask_.data());
        for (int x = x0; x <= x1; ++x) luma_a_[x] = luma_b_[x] = 0, mask_[x] = 0;
      }
    }
    if (drawn_a_ == 0 || drawn_b_ == 0) {
      IbsmView empty;
      empty.direction = direction;
      empty.ssim = empty.ms_ssim = std::numeric_limits<double>::quiet_NaN();
      empty.left_out = true;
      return empty;
    }
    if (o.image_quality && out.matched > 0) {
      const SsimScores q = ssim_.finish();
      out.ssim = q.ssim;
      out.ms_ssim = q.ms_ssim;
    }
    return out;
  }

 private:
  /// One row of both views over the columns [x0, x1] either draws: the pixels drawn, the errors
  /// where both are (in pixel order: the sums run over the view's pixels in order, band after
  /// band), and the SSIM's row: each view's luma (float, as mmetric's Y) and the pixels both
  /// cover (zero elsewhere).
  void compare_row(const std::uint8_t* a, const float* depth_a, const std::uint8_t* b,
                   const float* depth_b, int x0, int x1, float depth_range, IbsmView& out) {
    for (int x = x0; x <= x1; ++x) {
      const std::uint8_t* p = a + 4 * static_cast<std::size_t>(x);
      luma_a_[x] = luma_of(p[0], p[1], p[2]);
    }
    for (int x = x0; x <= x1; ++x) {
      const std::uint8_t* p = b + 4 * static_cast<std::size_t>(x);
      luma_b_[x] = luma_of(p[0], p[1], p[2]);
    }
    ErrorSums sums(out);
    std::size_t drawn_a = 0, drawn_b = 0;
    for (int x = x0; x <= x1; ++x) {
      const std::uint8_t* pa = a + 4 * static_cast<std::size_t>(x);
      const std::uint8_t* pb = b + 4 * static_cast<std::size_t>(x);
      const bool in_a = pa[3] != 0, in_b = pb[3] != 0;
      drawn_a += in_a;
      drawn_b += in_b;
      mask_[x] = in_a && in_b;
      if (in_a != in_b) ++sums.unmatched;
      if (!(in_a && in_b)) continue;
      ++sums.matched;
      sums.add(pa, depth_a[x], pb, depth_b[x], depth_range);
    }
    sums.store(out);
    drawn_a_ += drawn_a;
    drawn_b_ += drawn_b;
  }

  detail::BandRaster ref_, dist_;
  std::vector<std::uint8_t> rgba_a_, rgba_b_, mask_;
  std::vector<float> depth_a_, depth_b_;
  std::vector<double> luma_a_, luma_b_;
  detail::SsimStream ssim_;
  std::size_t drawn_a_ = 0, drawn_b_ = 0;
};

/// Written as every other output (write_file_atomically): a full disk or a write error leaves
/// no empty or truncated PNG behind and fails naming the file.
void write_png(const std::filesystem::path& path, const View& v) {
  const std::vector<std::uint8_t> png = png_bytes(v);
  write_file_atomically(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  });
}

std::string view_file(int index, const char* which) {
  char name[64];
  std::snprintf(name, sizeof name, "view_%02d_%s.png", index, which);
  return name;
}

int thread_count(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

/// Renders and compares every view (views in parallel, each written to its own slot; one
/// ViewScorer per thread, its buffers reused from view to view).
std::vector<IbsmView> compare_all_views(const RenderModel& ref, const RenderModel& dist,
                                        const Frame& frame, const std::vector<Float3>& dirs,
                                        const IbsmOptions& o) {
  std::vector<IbsmView> out(dirs.size());
  std::vector<std::exception_ptr> errors(dirs.size());
  const RasterOptions ro{o.resolution, o.culling, o.lighting};
  const int n = static_cast<int>(dirs.size());
  const int threads = std::max(1, std::min(thread_count(o.threads), n));
  std::vector<std::unique_ptr<ViewScorer>> scorers(static_cast<std::size_t>(threads));
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int i = 0; i < n; ++i) {
    try {
      if (!o.save_views.empty()) {
        write_png(o.save_views / view_file(i, "reference"), render_view(ref, frame, dirs[i], ro));
        write_png(o.save_views / view_file(i, "distorted"), render_view(dist, frame, dirs[i], ro));
      }
      auto& scorer = scorers[static_cast<std::size_t>(omp_get_thread_num())];
      if (!scorer) scorer = std::make_unique<ViewScorer>();
      out[i] = scorer->score(ref, dist, frame, dirs[i], o);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  }
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  return out;
}

double clipped_psnr(double mse) { return std::min(kPsnrClip, 10.0 * std::log10((255.0 * 255.0) / mse)); }

/// mmetric's pooling: sums over the views, / matched pixels, PSNRs clipped.
NamedValues pooled_values(const std::vector<IbsmView>& views, std::size_t& matched_out) {
  double rgb[3] = {0, 0, 0}, yuv[3] = {0, 0, 0}, depth = 0;
  std::size_t matched = 0, unmatched = 0;
  double ssim_sum = 0, ms_ssim_sum = 0;
  std::size_t ssim_views = 0, ms_ssim_views = 0;
  for (const IbsmView& v : views) {
    if (v.left_out) continue;
    for (int c = 0; c < 3; ++c) {
      rgb[c] += v.rgb_sse[c];
      yuv[c] += v.yuv_sse[c];
    }
    depth += v.depth_sse;
    matched += v.matched;
    unmatched += v.unmatched;
    if (!std::isnan(v.ssim)) ssim_sum += v.ssim, ++ssim_views;
    if (!std::isnan(v.ms_ssim)) ms_ssim_sum += v.ms_ssim, ++ms_ssim_views;
  }
  matched_out = matched;
  const double m = static_cast<double>(matched);
  double mse[9];
  for (int c = 0; c < 3; ++c) {
    mse[c] = rgb[c] / m;
    mse[4 + c] = yuv[c] / m;
  }
  mse[3] = (mse[0] + mse[1] + mse[2]) / 3.0;
  mse[7] = (mse[4] * 6.0 + mse[5] + mse[6]) / 8.0;
  mse[8] = depth / m;
  const std::vector<std::string>& names = ibsm_value_names();
  NamedValues out;
  for (int k = 0; k < 9; ++k) out.emplace_back(names[k], mse[k]);
  for (int k = 0; k < 9; ++k) out.emplace_back(names[9 + k], clipped_psnr(mse[k]));
  out.emplace_back("unmatched_pixel_percentage", 100.0 * static_cast<double>(unmatched) / m);
  if (ssim_views > 0) out.emplace_back("ssim", ssim_sum / static_cast<double>(ssim_views));
  if (ms_ssim_views > 0) out.emplace_back("ms_ssim", ms_ssim_sum / static_cast<double>(ms_ssim_views));
  return out;
}

nlohmann::json view_details(const IbsmView& v) {
  nlohmann::json j;
  j["direction"] = {v.direction[0], v.direction[1], v.direction[2]};
  j["left_out"] = v.left_out;
  j["matched_pixels"] = v.matched;
  j["unmatched_pixels"] = v.unmatched;
  auto finite_or_null = [](double x) { return std::isnan(x) ? nlohmann::json() : nlohmann::json(x); };
  const double m = static_cast<double>(v.matched);
  const double yuv_mse = v.matched ? (v.yuv_sse[0] * 6 + v.yuv_sse[1] + v.yuv_sse[2]) / 8 / m : NAN;
  j["yuv_psnr"] = finite_or_null(v.matched ? clipped_psnr(yuv_mse) : NAN);
  j["ssim"] = finite_or_null(v.ssim);
  j["ms_ssim"] = finite_or_null(v.ms_ssim);
  return j;
}

void check_options(const IbsmOptions& o) {
  if (o.views < 2) throw std::invalid_argument("views: at least 2 (mmetric divides by views - 1)");
  if (o.resolution < 16 || o.resolution > 16384) {
    throw std::invalid_argument("resolution: 16 to 16384 pixels (got " +
                                std::to_string(o.resolution) + ")");
  }
}

}  // namespace

std::vector<View> render_views(const RenderModel& model, const Frame& frame,
                               const std::vector<Float3>& directions, const RasterOptions& options,
                               int threads) {
  std::vector<View> out(directions.size());
  std::vector<std::exception_ptr> errors(directions.size());
  const int n = static_cast<int>(directions.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(thread_count(threads))
  for (int i = 0; i < n; ++i) {
    try {
      out[i] = render_view(model, frame, directions[i], options);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  }
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  return out;
}

MetricResult compute_ibsm(const RenderModel& reference, const RenderModel& distorted,
                          const IbsmOptions& options, const std::string& reference_name,
                          const std::string& distorted_name) {
  const auto start = std::chrono::steady_clock::now();
  check_options(options);
  const std::vector<Float3> dirs = view_directions(options);  // checks the layout's options
  if (!options.save_views.empty()) {
    std::error_code error;
    std::filesystem::create_directories(options.save_views, error);
    if (error || !std::filesystem::is_directory(options.save_views)) {
      throw InputError(options.save_views.string() + ": cannot create the views' directory" +
                       (error ? " (" + error.message() + ")" : ""));
    }
  }
  const Frame frame = frame_of(reference, distorted);
  const std::vector<IbsmView> views = compare_all_views(reference, distorted, frame, dirs, options);
  MetricResult r;
  r.metric = "ibsm";
  std::size_t left_out = 0;
  for (std::size_t i = 0; i < views.size(); ++i) {
    if (!views[i].left_out) continue;
    ++left_out;
    r.warnings.push_back("ibsm: view " + std::to_string(i) + ": " +
                         (reference_name + " or " + distorted_name) +
                         " draws nothing; view left out");
  }
  // The renderer works in float32 like mmetric's OpenGL: content far from the origin loses
  // precision against a pixel's footprint (the frame's diameter / resolution).
  const Float3& c = frame.center;
  const float half = frame.radius;
  const std::string far = float32_precision_warning(
      Vec3{c[0] - half, c[1] - half, c[2] - half}, Vec3{c[0] + half, c[1] + half, c[2] + half},
      2.0 * half / options.resolution, "pixel size",
      "ibsm: " + reference_name + ", " + distorted_name,
      "mmetric's renderer");
  if (!far.empty()) r.warnings.push_back(far);
  std::size_t matched = 0;
  NamedValues values = pooled_values(views, matched);
  if (matched == 0) {
    throw NumericError("ibsm: no pixel drawn by both " + reference_name + " and " + distorted_name +
                       " in any view (" + std::to_string(left_out) + " of " +
                       std::to_string(views.size()) + " views empty)");
  }
  DirectionResult d;
  d.score = find_value(values, "yuv_psnr").value();
  d.values = values;
  r.values = values;
  r.score = d.score;
  r.dist_to_ref = d;
  r.ref_to_dist = d;
  r.details["box_ratio"] = box_ratio(reference, distorted);
  r.details["bsphere_center"] = {frame.center[0], frame.center[1], frame.center[2]};
  r.details["bsphere_radius"] = frame.radius;
  r.details["views_left_out"] = left_out;
  r.details["render"] = {
      {"layout", options.layout == ViewLayout::kCmdm18 ? "cmdm18" : "fibonacci"},
      {"resolution", options.resolution},
      {"culling", options.culling},
      {"lighting", options.lighting == Lighting::kHeadlight ? "headlight" : "none"},
      {"splat_shape", options.splats.shape == SplatShape::kDisc ? "disc" : "square"}};
  if (reference.is_cloud()) r.details["splat_size_reference"] = reference.splat_size;
  if (distorted.is_cloud()) r.details["splat_size_distorted"] = distorted.splat_size;
  nlohmann::json per_view = nlohmann::json::array();
  for (const IbsmView& v : views) per_view.push_back(view_details(v));
  r.details["views"] = per_view;
  r.text_note = "YUV PSNR " + std::to_string(d.score) + " dB over " + std::to_string(dirs.size()) +
                " views";
  r.provenance.version = kVersion;
  r.provenance.reference = reference_name;
  r.provenance.distorted = distorted_name;
  r.provenance.seconds = seconds_since(start);
  return r;
}

}  // namespace qm3d::render

namespace qm3d::render {

RenderModel model_of(const Input& input, const SplatOptions& splats) {
  try {
    if (input.is_mesh() && !input.path().empty() && input.format() != FileFormat::kPcd) {
      const mesh::MeshFormat f = input.format() == FileFormat::kObj   ? mesh::MeshFormat::kObj
                                 : input.format() == FileFormat::kOff ? mesh::MeshFormat::kOff
                                                                      : mesh::MeshFormat::kPly;
      if (mesh::may_be_textured(input.path(), f, input.read_options())) {
        auto textured = mesh::read_textured_mesh(read_file_bytes(input.path()), f, input.path(),
                                                 input.read_options());
        if (textured) return textured_mesh_model(*textured);
      }
    }
    if (input.is_mesh()) {
      const MeshData& m = input.mesh();
      return mesh_model(m.mesh, m.has_colors);
    }
    return cloud_model(input.cloud(), splats);
  } catch (const FormatError& e) {
    throw FormatError(input.name() + ": " + e.what());
  }
}

namespace {

/// Both inputs read (when not yet) and made ready to draw at once, on two threads when the run
/// has them (sorting into the canonical order is most of a run's serial part). An error is the
/// one the sequential order raises: the reference's first.
void both_models(const Input& ref, const Input& dist, const IbsmOptions& o, RenderModel& a,
                 RenderModel& b) {
  const Input* in[2] = {&ref, &dist};
  RenderModel* out[2] = {&a, &b};
  std::exception_ptr errors[2];
#pragma omp parallel for schedule(static, 1) num_threads(std::min(2, thread_count(o.threads)))
  for (int i = 0; i < 2; ++i) {
    try {
      *out[i] = model_of(*in[i], o.splats);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  }
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

MetricResult run_ibsm(const MetricSpec&, const Input& ref, const Input& dist, const RunOptions& run,
                      const OptionValues& v) {
  const IbsmOptions o = ibsm_options(v, run);
  RenderModel a, b;
  both_models(ref, dist, o, a, b);
  // The mesh readers' repairs (the cloud readers' are added by run_metric).
  std::vector<std::string> warnings;
  for (const Input* in : {&ref, &dist}) {
    if (in->is_mesh()) {
      const auto& w = in->mesh().warnings;
      warnings.insert(warnings.end(), w.begin(), w.end());
    }
  }
  if (run.inputs_done) run.inputs_done();
  MetricResult r = compute_ibsm(a, b, o, ref.name(), dist.name());
  warnings.insert(warnings.end(), r.warnings.begin(), r.warnings.end());
  r.warnings = std::move(warnings);
  r.provenance.options = v;
  r.provenance.options.erase("save_views");
  return r;
}

}  // namespace

std::vector<Float3> view_directions(const IbsmOptions& options) {
  if (options.layout == ViewLayout::kCmdm18) {
    if (options.views != 16) {
      throw std::invalid_argument("views: applies to the fibonacci layout (cmdm18 has 18)");
    }
    if (options.rotation_deg[2] != 0) {
      throw std::invalid_argument("rotation: applies to the fibonacci layout");
    }
    return cmdm18_directions();
  }
  return fibonacci_directions(options.views, options.rotation_deg);
}

IbsmOptions ibsm_options(const OptionValues& v, const RunOptions& run) {
  IbsmOptions o;
  static_cast<RunOptions&>(o) = run;
  o.layout = v.at("layout").get<std::string>() == "cmdm18" ? ViewLayout::kCmdm18
                                                            : ViewLayout::kFibonacci;
  o.views = v.at("views").get<int>();
  o.resolution = v.at("resolution").get<int>();
  const nlohmann::json& r = v.at("rotation");
  o.rotation_deg = {r.at(0).get<float>(), r.at(1).get<float>(), r.at(2).get<float>()};
  o.culling = !v.at("no_culling").get<bool>();
  o.lighting = v.at("lighting").get<std::string>() == "headlight" ? Lighting::kHeadlight
                                                                   : Lighting::kUnlit;
  o.image_quality = !v.at("no_ssim").get<bool>();
  o.splats.size = v.at("splat_size").get<double>();
  o.splats.shape = v.at("splat_shape").get<std::string>() == "disc" ? SplatShape::kDisc
                                                                     : SplatShape::kSquare;
  o.save_views = v.at("save_views").get<std::string>();
  return o;
}

std::vector<std::uint8_t> png_bytes(const View& v) {
  // PNG has no empty image (width and height >= 1): stb would write one no reader opens.
  if (v.width < 1 || v.height < 1 ||
      v.rgba.size() != static_cast<std::size_t>(v.width) * static_cast<std::size_t>(v.height) * 4) {
    throw std::invalid_argument("png_bytes: a view of " + std::to_string(v.width) + "x" +
                                std::to_string(v.height) + " pixels with " +
                                std::to_string(v.rgba.size()) + " RGBA bytes");
  }
  std::vector<std::uint8_t> out;
  const auto append = [](void* context, void* data, int size) {
    auto* bytes = static_cast<std::vector<std::uint8_t>*>(context);
    const auto* p = static_cast<const std::uint8_t*>(data);
    bytes->insert(bytes->end(), p, p + size);
  };
  const std::uint8_t* last_row =
      v.rgba.data() + static_cast<std::size_t>(v.width) * 4 * (v.height - 1);
  if (!stbi_write_png_to_func(append, &out, v.width, v.height, 4, last_row, -v.width * 4)) {
    throw NumericError("PNG encoding of a view failed");
  }
  return out;
}

std::vector<ViewPair> result_view_pairs(const MetricResult& result, const Input& reference,
                                        const Input& distorted, int resolution, int threads) {
  if (result.metric != "ibsm" || !result.details.contains("render")) {
    throw std::invalid_argument("result_view_pairs: not an ibsm result");
  }
  const nlohmann::json& d = result.details;
  const nlohmann::json& render = d.at("render");
  SplatOptions ref_splats, dist_splats;
  ref_splats.shape = dist_splats.shape =
      render.at("splat_shape").get<std::string>() == "disc" ? SplatShape::kDisc : SplatShape::kSquare;
  if (d.contains("splat_size_reference")) ref_splats.size = d.at("splat_size_reference").get<double>();
  if (d.contains("splat_size_distorted")) dist_splats.size = d.at("splat_size_distorted").get<double>();
  const RenderModel a = model_of(reference, ref_splats);
  const RenderModel b = model_of(distorted, dist_splats);
  Frame frame;
  for (int k = 0; k < 3; ++k) frame.center[k] = d.at("bsphere_center").at(k).get<float>();
  frame.radius = d.at("bsphere_radius").get<float>();
  RasterOptions ro;
  ro.resolution = resolution;
  ro.culling = render.at("culling").get<bool>();
  ro.lighting = render.at("lighting").get<std::string>() == "headlight" ? Lighting::kHeadlight
                                                                        : Lighting::kUnlit;
  std::vector<Float3> dirs;
  for (const nlohmann::json& v : d.at("views")) {
    const nlohmann::json& dir = v.at("direction");
    dirs.push_back({dir.at(0).get<float>(), dir.at(1).get<float>(), dir.at(2).get<float>()});
  }
  std::vector<View> va = render_views(a, frame, dirs, ro, threads);
  std::vector<View> vb = render_views(b, frame, dirs, ro, threads);
  std::vector<ViewPair> out(dirs.size());
  for (std::size_t i = 0; i < dirs.size(); ++i) {
    out[i] = ViewPair{dirs[i], std::move(va[i]), std::move(vb[i])};
  }
  return out;
}

MetricSpec ibsm_spec() {
  MetricSpec s;
  s.name = "ibsm";
  s.title = "IBSM";
  s.reproduces = "MPEG mmetric 1.1.7 compare --mode ibsm, sw_raster (MPEGGroup/mpeg-pcc-mmetric @ 5faa660)";
  s.summary =
      "Image-based quality from rendered views (mmetric's IBSM: PSNR of RGB, YUV and depth over "
      "the pixels both objects cover, plus SSIM / MS-SSIM of the luma); meshes and point clouds "
      "(splats); score = YUV PSNR, dB";
  s.higher_is_better = true;
  s.applies_to = AppliesTo::kBoth;
  s.reads = Input::Kind::kCloud;
  s.reads_two_meshes_as_meshes = true;
  s.reads_each_as_is = true;
  s.in_compare = false;  // 2 x 16 views of 2048² and SSIM: asked for by name
  s.default_direction = Direction::kSymmetric;
  s.direction_help = "one comparison of the two images of each view (both directions are the same)";
  s.symmetric_rule = "the same image comparison";
  s.per_element_on_input = false;
  s.value_names = ibsm_value_names();
  for (const std::string& n : s.value_names) {
    if (n.find("_psnr") != std::string::npos || n == "ssim" || n == "ms_ssim") {
      s.quality_value_names.push_back(n);
    }
  }
  s.options = {
      {"views", "Views on a Fibonacci sphere (mmetric --ibsmCameraCount)", 16, {}, 2, 4096},
      {"resolution", "Width = height of each view, pixels (mmetric --ibsmResolution)", 2048, {}, 16,
       16384},
      {"rotation",
       "Rotation of the views: polar angle, azimuth, magnitude in degrees, applied when the "
       "magnitude is not 0 (mmetric --ibsmCameraRotation)",
       nlohmann::json::array({0.0, 0.0, 0.0})},
      {"layout",
       "Where the cameras are: fibonacci = --views directions on mmetric's Fibonacci sphere; "
       "cmdm18 = the 18 directions of the CMDM report's image metrics (6 axes + 12 plane "
       "diagonals)",
       "fibonacci", {"fibonacci", "cmdm18"}},
      {"no_culling", "Draw back faces too (mmetric --ibsmDisableCulling)", false},
      {"lighting",
       "none = the colours themselves (mmetric's); headlight = meshes shaded by a light at the "
       "camera, colour x (0.4 + 0.6 n.v) (mmetric's lit shader's constants)",
       "none", {"none", "headlight"}},
      {"no_ssim", "Leave out SSIM and MS-SSIM (faster)", false},
      {"splat_size",
       "Size of a point cloud's splats (diameter or side), world units; 0 = 6 x the median "
       "nearest-point spacing",
       0.0, {}, 0, 1e300},
      {"splat_shape", "Shape of a point cloud's splats: disc (of diameter --splat-size) or square",
       "disc", {"disc", "square"}},
      {"save_views", "Directory where each view of both inputs is written as PNG (empty: none)", ""},
  };
  s.run = run_ibsm;
  return s;
}

void register_metrics(Registry& registry) {
  registry.add(ibsm_spec());
  registry.add(icid_spec());
}

}  // namespace qm3d::render
