// A model drawn in one view band by band (raster.cpp): ibsm renders and scores its views a
// band of rows at a time, so that no whole view is held. The pixels are render_view's: a face
// or splat draws the same values into a pixel whatever rows are being drawn, and each band
// takes its items in the model's order.
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "qm3d/render/raster.h"

namespace qm3d::render::detail {

class BandRaster {
 public:
  BandRaster();
  ~BandRaster();
  BandRaster(const BandRaster&) = delete;
  BandRaster& operator=(const BandRaster&) = delete;

  /// Sets up `model` seen from `direction` (render_view's camera), its faces or splats listed
  /// per band of `band_rows` rows. The model must outlive the drawing; buffers are kept
  /// between views. std::invalid_argument for a resolution < 1.
  void prepare(const RenderModel& model, const Frame& frame, const Float3& direction,
               const RasterOptions& options, int band_rows);
  int width() const;
  int height() const;
  int bands() const;
  /// Rows [band * band_rows, min(height, (band + 1) * band_rows)).
  int band_row0(int band) const;
  int band_rows(int band) const;
  /// The frame's depth range in depth units (View::depth_range).
  float depth_range() const;
  /// Draws a band into rgba (4 bytes per pixel) and depth, width * band_rows(band) each,
  /// rows bottom first; clears them first (alpha 0, depth -FLT_MAX).
  void draw(int band, std::uint8_t* rgba, float* depth);
  /// After draw: the first and last column drawn in row `row` of the band (counted from the
  /// band's first row); {width, -1} when the row has no pixel drawn.
  std::array<int, 2> drawn_columns(int row) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace qm3d::render::detail
