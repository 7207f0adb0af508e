#include "qm3d/report/eval_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "qm3d/report/plot_canvas.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"

namespace qm3d::report {
namespace {

namespace fs = std::filesystem;

// Canvas and frame of the SVG, in pixels.
constexpr double kWidth = 720, kHeight = 540;
constexpr double kLeft = 80, kRight = 24, kTop = 48, kBottom = 64;
constexpr double kTickLength = 5;
constexpr double kPointRadius = 2.5;
constexpr double kMinBar = 2;  ///< the lowest bar drawn, in pixels
constexpr int kCurveSamples = 200;
constexpr double kTargetTicks = 6;
constexpr double kRangePadding = 0.04;  ///< fraction of the data range added on each side
constexpr const char* kPointColour = "#1f77b4";
constexpr const char* kCurveColour = "#d62728";

struct Range {
  double lo = 0, hi = 1;
};

Range padded_range(const std::vector<double>& values) {
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  double span = *hi - *lo;
  if (!(span > 0)) span = std::max(std::fabs(*lo), 1.0);
  return {*lo - kRangePadding * span, *hi + kRangePadding * span};
}

// 1, 2 or 5 times a power of ten, giving about kTargetTicks ticks over `span`.
double nice_step(double span) {
  const double raw = span / kTargetTicks;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double r = raw / magnitude;
  return (r < 1.5 ? 1 : r < 3 ? 2 : r < 7 ? 5 : 10) * magnitude;
}

std::vector<double> ticks(const Range& r) {
  const double step = nice_step(r.hi - r.lo);
  std::vector<double> out;
  for (double t = std::ceil(r.lo / step) * step; t <= r.hi + 1e-9 * step; t += step) {
    out.push_back(std::fabs(t) < 1e-12 * step ? 0.0 : t);
  }
  return out;
}

std::string format(const char* spec, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, spec, v);
  return buf;
}

struct Frame {
  Range x, y;
  double px(double v) const {
    return kLeft + (v - x.lo) / (x.hi - x.lo) * (kWidth - kLeft - kRight);
  }
  double py(double v) const {
    return kHeight - kBottom - (v - y.lo) / (y.hi - y.lo) * (kHeight - kTop - kBottom);
  }
};

using Anchor = Canvas::Anchor;

std::vector<double> curve_samples(const ScatterPlot& p, const Range& x) {
  std::vector<double> ys;
  for (int i = 0; i <= kCurveSamples; ++i)
    ys.push_back(p.curve(x.lo + (x.hi - x.lo) * i / kCurveSamples));
  return ys;
}

// The frame, the title and the label of the vertical axis, as both figures have them.
Canvas frame_canvas(const std::string& title, const std::string& y_label) {
  Canvas c;
  c.width = kWidth;
  c.height = kHeight;
  const double y0 = kHeight - kBottom, y1 = kTop;
  c.rect(kLeft, y1, kWidth - kRight - kLeft, y0 - y1, {}, 0, true);
  c.text(20, (y0 + y1) / 2, y_label, Anchor::kMiddle, 13, false, false, true);
  c.text(kWidth / 2, 28, title, Anchor::kMiddle, 13, true);
  return c;
}

void draw_axes(Canvas& c, const Frame& f, const ScatterPlot& p) {
  const double x0 = kLeft, x1 = kWidth - kRight, y0 = kHeight - kBottom;
  for (double t : ticks(f.x)) {
    c.line({f.px(t), y0, f.px(t), y0 + kTickLength}, {});
    c.text(f.px(t), y0 + 20, format("%.4g", t), Anchor::kMiddle);
  }
  for (double t : ticks(f.y)) {
    c.line({x0 - kTickLength, f.py(t), x0, f.py(t)}, {});
    c.text(x0 - 8, f.py(t), format("%.4g", t), Anchor::kEnd, 13, false, true);
  }
  c.text((x0 + x1) / 2, kHeight - 18, p.x_label, Anchor::kMiddle);
}

Canvas scatter_canvas(const ScatterPlot& p) {
  Frame f;
  f.x = padded_range(p.x);
  const std::vector<double> curve = curve_samples(p, f.x);
  std::vector<double> all_y = p.y;
  all_y.insert(all_y.end(), curve.begin(), curve.end());
  f.y = padded_range(all_y);
  Canvas c = frame_canvas(p.title, p.y_label);
  draw_axes(c, f, p);
  for (std::size_t i = 0; i < p.x.size(); ++i) {
    c.circle(f.px(p.x[i]), f.py(p.y[i]), kPointRadius, rgb(kPointColour), 0.5);
  }
  std::vector<double> xy;
  for (int i = 0; i <= kCurveSamples; ++i) {
    xy.push_back(f.px(f.x.lo + (f.x.hi - f.x.lo) * i / kCurveSamples));
    xy.push_back(f.py(curve[static_cast<std::size_t>(i)]));
  }
  c.line(std::move(xy), rgb(kCurveColour), 2);
  return c;
}

// The AUC axis: from chance (0.5), or lower (a multiple of 0.1) so that every bar and interval
// starts inside it (an AUC below 0.5 ranks the pairs worse than chance), up to 1.
Range auc_range(const AucPlot& p) {
  double lo = 0.5;
  for (std::size_t m = 0; m < p.names.size(); ++m) {
    for (const auto& [v, se] :
         {std::pair(p.auc_ds[m], p.se_ds[m]), std::pair(p.auc_bw[m], p.se_bw[m])}) {
      if (std::isfinite(v)) lo = std::min(lo, v - (std::isfinite(se) ? 1.96 * se : 0.0));
    }
  }
  return {std::max(0.0, std::floor(lo * 10 - 1e-9) / 10), 1.0};
}

Canvas auc_canvas(const AucPlot& p) {
  const std::size_t n = p.names.size();
  if (n == 0 || p.auc_ds.size() != n || p.auc_bw.size() != n || p.se_ds.size() != n ||
      p.se_bw.size() != n) {
    throw std::invalid_argument("AUC plot: no metric, or values of different lengths");
  }
  Frame f;
  f.y = auc_range(p);
  const double x0 = kLeft, x1 = kWidth - kRight, y0 = kHeight - kBottom;
  const auto py = [&](double auc) { return f.py(std::clamp(auc, f.y.lo, f.y.hi)); };
  Canvas c = frame_canvas(p.title, "AUC (0.5 = chance)");
  for (int k = 0; f.y.lo + 0.1 * k <= 1 + 1e-9; ++k) {
    const double v = f.y.lo + 0.1 * k, y = py(v);
    c.line({x0 - kTickLength, y, x1, y},
           std::fabs(v - 0.5) < 1e-9 ? rgb("#888888") : rgb("#dddddd"));
    c.text(x0 - 8, y, format("%.1f", v), Anchor::kEnd, 13, false, true);
  }
  const double slot = (x1 - x0) / static_cast<double>(n), bar = slot * 0.3;
  const Rgb colours[2] = {rgb(kPointColour), rgb(kCurveColour)};
  for (std::size_t m = 0; m < n; ++m) {
    const double centre = x0 + slot * (static_cast<double>(m) + 0.5);
    const double values[2] = {p.auc_ds[m], p.auc_bw[m]}, errors[2] = {p.se_ds[m], p.se_bw[m]};
    for (int b = 0; b < 2; ++b) {
      if (!std::isfinite(values[b])) continue;
      // At least kMinBar high, so that an AUC at the axis' foot (0) still shows; its value
      // written above it.
      const double left = centre + (b == 0 ? -bar : 0.0),
                   top = std::min(py(values[b]), y0 - kMinBar);
      c.rect(left, top, bar * 0.95, y0 - top, colours[b], 0.7, false);
      c.text(left + bar * 0.475, top - 4, format("%.2f", values[b]), Anchor::kMiddle, 11);
      const double mid = left + bar * 0.475;
      c.line({mid, py(values[b] - 1.96 * errors[b]), mid, py(values[b] + 1.96 * errors[b])}, {});
    }
    c.text(centre, y0 + 20, p.names[m], Anchor::kMiddle);
  }
  // The legend: a swatch and a label per bar, then what the whiskers are.
  const double y = kHeight - 18;
  double x = kLeft;
  const char* labels[2] = {"AUC_DS (different vs similar)", "AUC_BW (better vs worse)"};
  for (int b = 0; b < 2; ++b) {
    c.rect(x, y - 9, 9, 9, colours[b], 1, false);
    c.text(x + 13, y, labels[b], Anchor::kStart, 11, false, false, false, colours[b]);
    x += 220;
  }
  c.text(x1, y, "whiskers: 95 % DeLong intervals", Anchor::kEnd, 11);
  return c;
}

}  // namespace

void write_auc_plot(const fs::path& path, const AucPlot& p) { write_canvas(path, auc_canvas(p)); }

void write_scatter_plot(const fs::path& path, const ScatterPlot& plot) {
  if (plot.x.empty() || plot.x.size() != plot.y.size()) {
    throw std::invalid_argument("scatter plot: no points, or x and y of different lengths");
  }
  write_canvas(path, scatter_canvas(plot));
}

}  // namespace qm3d::report
