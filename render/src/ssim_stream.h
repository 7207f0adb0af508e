// Masked SSIM and MS-SSIM of two grey images fed one row at a time (image_quality.h's rules and
// values, bit for bit): each scale keeps only the rows its Gaussian window still needs (a ring
// of kRingRows rows) and passes every two rows down to the next scale as one halved row, so two
// whole images are never held. ibsm renders its views in bands of rows and scores them as they
// come; masked_ssim_scores feeds a whole image.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "qm3d/render/image_quality.h"

namespace qm3d::render::detail {

class SsimStream {
 public:
  SsimStream();
  ~SsimStream();
  SsimStream(const SsimStream&) = delete;
  SsimStream& operator=(const SsimStream&) = delete;

  /// Starts a pair of width x height images (the buffers are kept between images).
  void begin(int width, int height);
  /// The next row (rows in order, 0 first): both images' values and the mask (non-zero = in).
  void push_row(const double* a, const double* b, const std::uint8_t* mask);
  /// After the last row: SSIM and MS-SSIM over the mask (NaN as image_quality.h says).
  SsimScores finish() const;

 private:
  struct Scale;
  void push(int scale, const double* a, const double* b, const std::uint8_t* mask);
  std::vector<std::unique_ptr<Scale>> scales_;
};

}  // namespace qm3d::render::detail
