// One description of a figure, written as SVG or rasterised to PNG by the same geometry, so the
// two formats of `qm3d eval --plot` show the same figure (no external plotting program).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace qm3d::report {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};

/// "#rrggbb".
Rgb rgb(const char* hex);

/// The shapes of a figure, in pixels (y downwards), drawn in order.
struct Canvas {
  enum class Anchor { kStart, kMiddle, kEnd };
  struct Rect {
    double x, y, w, h;
    Rgb fill;
    double fill_opacity;  ///< 0: not filled
    bool stroke;          ///< a black outline
  };
  struct Line {
    std::vector<double> xy;  ///< x0 y0 x1 y1 ... (a polyline)
    Rgb colour;
    double width;
  };
  struct Circle {
    double x, y, r;
    Rgb fill;
    double opacity;
  };
  struct Text {
    double x, y;  ///< the anchor point; y: the baseline, or the middle with `centred`
    std::string text;
    Anchor anchor;
    double size;
    bool bold, centred, vertical;  ///< vertical: turned 90 degrees anticlockwise about (x, y)
    Rgb colour;
  };
  double width = 0, height = 0;
  std::vector<Rect> rects;
  std::vector<Line> lines;
  std::vector<Circle> circles;
  std::vector<Text> texts;
  /// Drawing order: (kind, index) with kind 0 rect, 1 line, 2 circle, 3 text.
  std::vector<std::pair<int, std::size_t>> order;

  void rect(double x, double y, double w, double h, Rgb fill, double opacity, bool stroke);
  void line(std::vector<double> xy, Rgb colour, double width = 1);
  void circle(double x, double y, double r, Rgb fill, double opacity);
  void text(double x, double y, std::string s, Anchor anchor, double size = 13, bool bold = false,
            bool centred = false, bool vertical = false, Rgb colour = {});
};

std::string canvas_svg(const Canvas& c);
/// The PNG file's bytes (8-bit RGB).
std::string canvas_png(const Canvas& c);

/// Writes `c` to `path` (atomically) as `.svg` or `.png`.
/// @throws InputError  another extension, or a write error
void write_canvas(const std::filesystem::path& path, const Canvas& c);

}  // namespace qm3d::report
