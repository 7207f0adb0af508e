// iCID, the improved colour-image-difference metric (Preiss, Fernandes & Urban, "Color-image
// quality assessment: from prediction to optimization", IEEE TIP 23(3) 2014), as the authors'
// MATLAB code computes it (iCID.m v1.00, vendored in Netflix/vmaf matlab/cid_icid/iCID/iCID_Metric
// @ f85a853). Rules: /work/shared/docs/SPEC-ICID.md; each is written down where it lives
// (render/src/icid.cpp). Also qm3d's image comparison of two 8-bit sRGB images (iCID, SSIM,
// MS-SSIM, PSNR) and the registry metric `icid` on rendered views.
//
// iCID is a distortion: 0 for identical images (without the appearance model, to ~1e-14: the
// structure terms compare a covariance with a product of clipped deviations), higher = more
// different. The seven maps are, in the reference's order: 1 lightness difference, 2 lightness
// contrast, 3 lightness structure, 4 chroma difference, 5 hue difference, 6 chroma contrast,
// 7 chroma structure; m_k = mean of 1 - inv_k over the maps' area (before the exponents).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "qm3d/common/color.h"
#include "qm3d/common/metric.h"

namespace qm3d::render {

/// An 8-bit sRGB image, top row first, 3 bytes (R, G, B) per pixel.
struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  ///< width * height * 3
};

/// Reads a PNG or JPEG (8 bits per channel; grey and palette images expanded to RGB, an alpha
/// channel dropped as the reference's imread does). InputError naming the file when it is
/// missing or unreadable, FormatError when it is not an 8-bit PNG / JPEG or has no pixels.
RgbImage read_rgb_image(const std::filesystem::path& path);

/// iCID's prediction intent (the constants c4, c5 of the chroma and hue terms).
enum class IcidIntent { kPerceptual, kHuePreserving, kChromatic };

struct IcidOptions {
  IcidIntent intent = IcidIntent::kPerceptual;
  bool iam = true;           ///< the iCAM_YCC appearance model (CSF filtering); false = 'NONE'
  bool omit_maps67 = false;  ///< exponents of maps 6 and 7 set to 0
  bool downsampling = true;  ///< automatic downsampling to ~256 px on the shorter side
  bool keep_map = false;     ///< fill IcidResult::map
  int threads = 0;           ///< OpenMP threads (0 = OpenMP's default): the same bits for any
};

/// "perceptual", "hue-preserving", "chromatic" -> the intent; std::invalid_argument otherwise.
IcidIntent icid_intent(const std::string& name);

/// The names of the seven map means, in the reference's order ("icid_m1" ... "icid_m7").
const std::array<std::string, 7>& icid_map_names();

struct IcidResult {
  double icid = 0;                    ///< 1 - mean of prod_k inv_k^e_k
  std::array<double, 7> maps{};       ///< m1 ... m7
  int map_width = 0, map_height = 0;  ///< the maps' area: the (downsampled) image less 5 px a side
  /// With IcidOptions::keep_map: 1 - prod_k inv_k^e_k per pixel of the maps' area, row-major.
  std::vector<double> map;
};

/// The directory of iCID's full-precision LAB2000HL tables: resolve_data_dir(data_dir) / "icid"
/// (the PCQM tables there are rounded to 4 decimals; iCID needs the originals).
std::filesystem::path icid_table_dir(const std::filesystem::path& data_dir = {});

/// iCID of two images of the same size. std::invalid_argument when the sizes differ or the
/// (downsampled) images are smaller than the 11 x 11 window.
IcidResult icid(const RgbImage& a, const RgbImage& b, const Lab2000hlTable& table,
                const IcidOptions& options = {});

/// Every score of `qm3d image` / qm3d.image_quality: iCID and its maps, SSIM and MS-SSIM of the
/// BT.709 luma over the whole image (image_quality.h), PSNR of R, G, B together (8-bit; +inf for
/// identical images).
struct ImageScores {
  IcidResult icid;
  double ssim = 0, ms_ssim = 0, psnr = 0;
};
ImageScores image_scores(const RgbImage& a, const RgbImage& b, const Lab2000hlTable& table,
                         const IcidOptions& options = {});

/// The registry entry: metric `icid` for meshes and clouds (rendered views, iCID per view pair,
/// their mean).
MetricSpec icid_spec();

}  // namespace qm3d::render
