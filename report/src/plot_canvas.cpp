#include "qm3d/report/plot_canvas.h"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#include <stb/stb_easy_font.h>
#pragma GCC diagnostic pop
#include <stb/stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "markup.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"

namespace qm3d::report {
namespace {

/// stb_easy_font's glyphs: capitals are 7 units tall from the top of the line; a 13 px SVG font
/// (cap height about 0.7 em) matches a scale of 13 / 10.
constexpr double kFontUnitsPerEm = 10;
constexpr double kCapUnits = 7;

std::string hex(Rgb c) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c.r, c.g, c.b);
  return buf;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

const char* anchor_name(Canvas::Anchor a) {
  return a == Canvas::Anchor::kStart ? "start" : a == Canvas::Anchor::kMiddle ? "middle" : "end";
}

// ---- raster --------------------------------------------------------------------------------

class Raster {
 public:
  Raster(int w, int h) : w_(w), h_(h), px_(static_cast<std::size_t>(w) * h * 3, 255) {}

  void blend(int x, int y, Rgb c, double a) {
    if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
    unsigned char* p = &px_[(static_cast<std::size_t>(y) * w_ + x) * 3];
    const std::uint8_t v[3] = {c.r, c.g, c.b};
    for (int k = 0; k < 3; ++k)
      p[k] = static_cast<unsigned char>(std::lround(p[k] + a * (v[k] - p[k])));
  }
  // Pixels whose centre lies in [x0, x1) x [y0, y1).
  void fill(double x0, double y0, double x1, double y1, Rgb c, double a) {
    const int xa = static_cast<int>(std::ceil(std::min(x0, x1) - 0.5));
    const int xb = static_cast<int>(std::ceil(std::max(x0, x1) - 0.5));
    const int ya = static_cast<int>(std::ceil(std::min(y0, y1) - 0.5));
    const int yb = static_cast<int>(std::ceil(std::max(y0, y1) - 0.5));
    for (int y = std::max(ya, 0); y < std::min(yb, h_); ++y) {
      for (int x = std::max(xa, 0); x < std::min(xb, w_); ++x) blend(x, y, c, a);
    }
  }
  void segment(double x0, double y0, double x1, double y1, Rgb c, double width) {
    const double length = std::hypot(x1 - x0, y1 - y0);
    const int steps = std::max(1, static_cast<int>(std::ceil(length * 2)));
    const double half = std::max(width, 1.0) / 2;
    for (int i = 0; i <= steps; ++i) {
      const double x = x0 + (x1 - x0) * i / steps, y = y0 + (y1 - y0) * i / steps;
      fill(x - half, y - half, x + half, y + half, c, 1);
    }
  }
  void disc(double cx, double cy, double r, Rgb c, double a) {
    for (int y = static_cast<int>(cy - r) - 1; y <= static_cast<int>(cy + r) + 1; ++y) {
      for (int x = static_cast<int>(cx - r) - 1; x <= static_cast<int>(cx + r) + 1; ++x) {
        if (std::hypot(x + 0.5 - cx, y + 0.5 - cy) <= r) blend(x, y, c, a);
      }
    }
  }
  void text(const Canvas::Text& t) {
    std::string s = t.text;
    for (char& ch : s) {
      if (static_cast<unsigned char>(ch) < 32 || static_cast<unsigned char>(ch) > 126) ch = '?';
    }
    const double scale = t.size / kFontUnitsPerEm;
    const double width = stb_easy_font_width(s.data()) * scale;
    const double u0 = t.anchor == Canvas::Anchor::kStart    ? 0
                      : t.anchor == Canvas::Anchor::kMiddle ? -width / 2
                                                            : -width;
    const double v0 = -(t.centred ? kCapUnits / 2 : kCapUnits) * scale;
    std::vector<float> quads(s.size() * 300);
    const int n = stb_easy_font_print(0, 0, s.data(), nullptr, quads.data(),
                                      static_cast<int>(quads.size() * sizeof(float)));
    for (int q = 0; q < n; ++q) {
      const float* v = &quads[static_cast<std::size_t>(q) * 16];  // 4 vertices of 4 floats
      // Bold: each glyph stroke drawn twice, a third of a unit apart.
      for (int pass = 0; pass < (t.bold ? 2 : 1); ++pass) {
        const double du = pass * scale / 3;
        const double ua = u0 + v[0] * scale + du, ub = u0 + v[8] * scale + du;
        const double va = v0 + v[1] * scale, vb = v0 + v[9] * scale;
        if (t.vertical) {  // (u, v) -> (x + v, y - u)
          fill(t.x + va, t.y - ub, t.x + vb, t.y - ua, t.colour, 1);
        } else {
          fill(t.x + ua, t.y + va, t.x + ub, t.y + vb, t.colour, 1);
        }
      }
    }
  }
  std::string png() const {
    std::string out;
    stbi_write_png_to_func(
        [](void* context, void* data, int size) {
          static_cast<std::string*>(context)->append(static_cast<const char*>(data),
                                                     static_cast<std::size_t>(size));
        },
        &out, w_, h_, 3, px_.data(), w_ * 3);
    return out;
  }

 private:
  int w_, h_;
  std::vector<unsigned char> px_;
};

}  // namespace

Rgb rgb(const char* h) {
  unsigned r = 0, g = 0, b = 0;
  std::sscanf(h, "#%02x%02x%02x", &r, &g, &b);
  return {static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g), static_cast<std::uint8_t>(b)};
}

void Canvas::rect(double x, double y, double w, double h, Rgb fill, double opacity, bool stroke) {
  rects.push_back({x, y, w, h, fill, opacity, stroke});
  order.emplace_back(0, rects.size() - 1);
}
void Canvas::line(std::vector<double> xy, Rgb colour, double w) {
  lines.push_back({std::move(xy), colour, w});
  order.emplace_back(1, lines.size() - 1);
}
void Canvas::circle(double x, double y, double r, Rgb fill, double opacity) {
  circles.push_back({x, y, r, fill, opacity});
  order.emplace_back(2, circles.size() - 1);
}
void Canvas::text(double x, double y, std::string s, Anchor anchor, double size, bool bold,
                  bool centred, bool vertical, Rgb colour) {
  texts.push_back({x, y, std::move(s), anchor, size, bold, centred, vertical, colour});
  order.emplace_back(3, texts.size() - 1);
}

std::string canvas_svg(const Canvas& c) {
  std::ostringstream out;
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" "
      << "width=\"" << c.width << "\" height=\"" << c.height << "\" viewBox=\"0 0 " << c.width
      << " " << c.height << "\" font-family=\"sans-serif\" font-size=\"13\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  for (const auto& [kind, i] : c.order) {
    if (kind == 0) {
      const Canvas::Rect& r = c.rects[i];
      out << "<rect x=\"" << num(r.x) << "\" y=\"" << num(r.y) << "\" width=\"" << num(r.w)
          << "\" height=\"" << num(r.h) << "\" fill=\""
          << (r.fill_opacity > 0 ? hex(r.fill) : "none") << "\""
          << (r.fill_opacity > 0 && r.fill_opacity < 1
                  ? " fill-opacity=\"" + num(r.fill_opacity) + "\""
                  : "")
          << (r.stroke ? " stroke=\"black\"" : "") << "/>\n";
    } else if (kind == 1) {
      const Canvas::Line& l = c.lines[i];
      out << "<polyline fill=\"none\" stroke=\"" << hex(l.colour) << "\" stroke-width=\"" << l.width
          << "\" points=\"";
      for (std::size_t k = 0; k + 1 < l.xy.size(); k += 2) {
        out << (k ? " " : "") << num(l.xy[k]) << "," << num(l.xy[k + 1]);
      }
      out << "\"/>\n";
    } else if (kind == 2) {
      const Canvas::Circle& d = c.circles[i];
      out << "<circle cx=\"" << num(d.x) << "\" cy=\"" << num(d.y) << "\" r=\"" << d.r
          << "\" fill=\"" << hex(d.fill) << "\" fill-opacity=\"" << num(d.opacity) << "\"/>\n";
    } else {
      const Canvas::Text& t = c.texts[i];
      out << "<text "
          << (t.vertical ? "transform=\"translate(" + num(t.x) + "," + num(t.y) + ") rotate(-90)\""
                         : "x=\"" + num(t.x) + "\" y=\"" + num(t.y) + "\"")
          << " text-anchor=\"" << anchor_name(t.anchor) << "\" font-size=\"" << t.size << "\""
          << (t.centred ? " dominant-baseline=\"middle\"" : "")
          << (t.bold ? " font-weight=\"bold\"" : "") << " fill=\"" << hex(t.colour) << "\">"
          << markup_escaped(t.text) << "</text>\n";
    }
  }
  out << "</svg>\n";
  return out.str();
}

std::string canvas_png(const Canvas& c) {
  Raster r(static_cast<int>(std::lround(c.width)), static_cast<int>(std::lround(c.height)));
  for (const auto& [kind, i] : c.order) {
    if (kind == 0) {
      const Canvas::Rect& x = c.rects[i];
      if (x.fill_opacity > 0) r.fill(x.x, x.y, x.x + x.w, x.y + x.h, x.fill, x.fill_opacity);
      if (x.stroke) {
        const double xs[5] = {x.x, x.x + x.w, x.x + x.w, x.x, x.x};
        const double ys[5] = {x.y, x.y, x.y + x.h, x.y + x.h, x.y};
        for (int k = 0; k < 4; ++k) r.segment(xs[k], ys[k], xs[k + 1], ys[k + 1], Rgb{}, 1);
      }
    } else if (kind == 1) {
      const Canvas::Line& l = c.lines[i];
      for (std::size_t k = 0; k + 3 < l.xy.size(); k += 2) {
        r.segment(l.xy[k], l.xy[k + 1], l.xy[k + 2], l.xy[k + 3], l.colour, l.width);
      }
    } else if (kind == 2) {
      const Canvas::Circle& d = c.circles[i];
      r.disc(d.x, d.y, d.r, d.fill, d.opacity);
    } else {
      r.text(c.texts[i]);
    }
  }
  return r.png();
}

void write_canvas(const std::filesystem::path& path, const Canvas& c) {
  const std::string ext = lower_extension(path);
  if (ext != "svg" && ext != "png") {
    throw InputError(path.string() + ": unknown plot format \"" + ext + "\" (use .svg or .png)");
  }
  const std::string bytes = ext == "svg" ? canvas_svg(c) : canvas_png(c);
  write_file_atomically(path, [&](std::ostream& out) { out << bytes; });
}

}  // namespace qm3d::report
