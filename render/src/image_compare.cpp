// Two 8-bit images read and compared (qm3d/render/icid.h: read_rgb_image, image_scores).
#include <stb/stb_image.h>

#include <cmath>
#include <limits>
#include <memory>

#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/render/icid.h"
#include "qm3d/render/image_quality.h"

namespace qm3d::render {
namespace {

constexpr int kRgbChannels = 3;
// Largest image file read (bytes): well above any snapshot, far below what exhausts memory.
constexpr std::uintmax_t kMaxImageBytes = std::uintmax_t(1) << 30;
// BT.709 luma weights (ITU-R BT.709-6, item 3.2), the grey image SSIM compares.
constexpr double kLumaR = 0.2126, kLumaG = 0.7152, kLumaB = 0.0722;
constexpr double kPeak8Bit = 255.0;

bool is_png(const std::string& bytes) { return bytes.rfind("\x89PNG\r\n\x1a\n", 0) == 0; }
bool is_jpeg(const std::string& bytes) { return bytes.rfind("\xFF\xD8\xFF", 0) == 0; }

GreyImage luma(const RgbImage& image) {
  GreyImage g{image.width, image.height, {}};
  g.values.resize(static_cast<std::size_t>(image.width) * image.height);
  for (std::size_t i = 0; i < g.values.size(); ++i) {
    const std::uint8_t* p = &image.rgb[3 * i];
    g.values[i] = kLumaR * p[0] + kLumaG * p[1] + kLumaB * p[2];
  }
  return g;
}

double rgb_psnr(const RgbImage& a, const RgbImage& b) {
  double sse = 0;
  for (std::size_t i = 0; i < a.rgb.size(); ++i) {
    const double d = static_cast<double>(a.rgb[i]) - static_cast<double>(b.rgb[i]);
    sse += d * d;
  }
  if (sse == 0) return std::numeric_limits<double>::infinity();
  const double mse = sse / static_cast<double>(a.rgb.size());
  return 10.0 * std::log10(kPeak8Bit * kPeak8Bit / mse);
}

}  // namespace

RgbImage read_rgb_image(const std::filesystem::path& path) {
  const std::string bytes = read_file_bytes(path, kMaxImageBytes);
  const std::string name = path.string();
  if (!is_png(bytes) && !is_jpeg(bytes)) throw FormatError(name + ": not a PNG or JPEG image");
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const int size = static_cast<int>(bytes.size());
  if (stbi_is_16_bit_from_memory(data, size)) {
    throw FormatError(name + ": 16 bits per channel; 8-bit images only");
  }
  int w = 0, h = 0, channels = 0;
  const std::unique_ptr<unsigned char, void (*)(void*)> pixels(
      stbi_load_from_memory(data, size, &w, &h, &channels, kRgbChannels), stbi_image_free);
  if (!pixels) {
    throw FormatError(name + ": cannot decode the image (" + stbi_failure_reason() + ")");
  }
  if (w <= 0 || h <= 0) throw FormatError(name + ": the image has no pixels");
  RgbImage image{w, h, {}};
  image.rgb.assign(pixels.get(), pixels.get() + static_cast<std::size_t>(w) * h * kRgbChannels);
  return image;
}

ImageScores image_scores(const RgbImage& a, const RgbImage& b, const Lab2000hlTable& table,
                         const IcidOptions& options) {
  ImageScores s;
  s.icid = icid(a, b, table, options);  // checks the sizes first
  const std::vector<std::uint8_t> everywhere(a.rgb.size() / 3, 1);
  const SsimScores q = masked_ssim_scores(luma(a), luma(b), everywhere);
  s.ssim = q.ssim;
  s.ms_ssim = q.ms_ssim;
  s.psnr = rgb_psnr(a, b);
  return s;
}

}  // namespace qm3d::render
