// IBSM: image-based quality of two objects from rendered views (mmetric 1.1.7's `compare --mode
// ibsm` with the sw_raster renderer: MPEGGroup/mpeg-pcc-mmetric @ 5faa660, mmCompare.cpp
// `Compare::ibsm`), plus SSIM and MS-SSIM of the luma (image_quality.h).
//
// Both objects are rendered (raster.h) from the same `views` directions of a Fibonacci sphere,
// framed on the bounding sphere of both. Over the pixels both images cover, summed over all
// views (mmetric's pooling): the MSE of R, G, B, of their mean (RGB), of BT.709 Y, U, V
// (mmetric's rgbToYuvBt709_256, 0..255) and of 6:1:1 YUV, the depth MSE scaled to 255 by the
// view's depth range (GEO), their PSNRs 10 log10(255^2 / MSE) clipped at kPsnrClip as mmetric
// prints them, and the unmatched pixels (covered by one image only) in % of the matched ones.
// SSIM / MS-SSIM: per view over the pixels both images cover, then their mean over the views.
//
// Where qm3d differs from mmetric, on purpose: a point cloud is drawn (splats, raster.h) where
// mmetric draws nothing and reports 99.99 dB; a view where either object draws nothing is left
// out with a warning (NumericError when every view is), never pooled as "perfect".
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "qm3d/common/metric.h"
#include "qm3d/common/result.h"
#include "qm3d/render/raster.h"

namespace qm3d::render {

/// mmetric's CLIP (mmStatistics.h): the PSNR it prints for identical images.
constexpr double kPsnrClip = 99.99;

/// The named values of an IBSM result, in order (the JSON `features`).
const std::vector<std::string>& ibsm_value_names();

/// Where the cameras are.
enum class ViewLayout {
  kFibonacci,  ///< `views` directions on mmetric's Fibonacci sphere, rotated by rotation_deg
  kCmdm18,     ///< the 18 directions of the CMDM report's protocol (raster.h cmdm18_directions)
};

struct IbsmOptions : RunOptions {
  ViewLayout layout = ViewLayout::kFibonacci;
  int views = 16;          ///< --ibsmCameraCount (Fibonacci layout)
  int resolution = 2048;   ///< --ibsmResolution (width = height)
  Float3 rotation_deg{0, 0, 0};  ///< --ibsmCameraRotation: polar, azimuth, magnitude (degrees)
  bool culling = true;     ///< false = --ibsmDisableCulling
  Lighting lighting = Lighting::kUnlit;  ///< unlit = mmetric's
  bool image_quality = true;  ///< compute SSIM and MS-SSIM (the slowest part)
  SplatOptions splats;     ///< how clouds are drawn
  /// When not empty: each view of both objects written there as PNG (view_NN_reference.png,
  /// view_NN_distorted.png; top row first), the directory created if needed.
  std::filesystem::path save_views;
};

/// The numbers of one view (before pooling).
struct IbsmView {
  Float3 direction{0, 0, 0};
  std::size_t matched = 0;    ///< pixels both images cover
  std::size_t unmatched = 0;  ///< pixels one image covers
  double rgb_sse[3] = {0, 0, 0};
  double yuv_sse[3] = {0, 0, 0};
  double depth_sse = 0;
  double ssim = 0, ms_ssim = 0;  ///< NaN when not computed
  bool left_out = false;          ///< an image is empty
};

/// The view directions of `options` (its layout, count and rotation); std::invalid_argument
/// when the cmdm18 layout is given a count or a rotation.
std::vector<Float3> view_directions(const IbsmOptions& options);

/// The options of an ibsm run from the registry's option values (all filled; ibsm_spec()).
IbsmOptions ibsm_options(const OptionValues& values, const RunOptions& run = {});

/// Compares two prepared models. NumericError when no view has pixels both images cover.
MetricResult compute_ibsm(const RenderModel& reference, const RenderModel& distorted,
                          const IbsmOptions& options, const std::string& reference_name = "reference",
                          const std::string& distorted_name = "distorted");

/// The model of an input: a textured OBJ with its textures (textured_mesh_model), another mesh
/// with its vertex colours (mesh_model) or, for a cloud, its points as splats (cloud_model).
RenderModel model_of(const Input& input, const SplatOptions& splats = {});

/// A view as a PNG file's bytes (RGBA, 8 bits, top row first, alpha 0 where nothing is drawn).
/// @throws std::invalid_argument  an empty view (PNG has none) or one whose RGBA bytes are not
///                                4 a pixel
std::vector<std::uint8_t> png_bytes(const View& view);

/// The view pairs of an ibsm result (its cameras, frame, culling, lighting and splat sizes, from
/// result.details) rendered again from `reference` and `distorted` at `resolution` pixels, for
/// display (the HTML report). std::invalid_argument when `result` is not an ibsm result.
struct ViewPair {
  Float3 direction{0, 0, 0};
  View reference, distorted;
};
std::vector<ViewPair> result_view_pairs(const MetricResult& result, const Input& reference,
                                        const Input& distorted, int resolution, int threads = 0);

/// The views of one object as compute_ibsm renders them (framed on `frame`; the frame of the
/// object alone is frame_of(model, model)), rendered with `threads` threads (0 = OpenMP's
/// default): the same images for any count.
std::vector<View> render_views(const RenderModel& model, const Frame& frame,
                               const std::vector<Float3>& directions, const RasterOptions& options,
                               int threads = 0);

/// The registry entry: metric `ibsm` for meshes and clouds (any pair).
MetricSpec ibsm_spec();
/// Registers ibsm and icid (icid.h).
void register_metrics(Registry& registry);

}  // namespace qm3d::render
