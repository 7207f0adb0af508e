#include "eval_plot.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "markup.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"

extern char** environ;

namespace qm3d::app {
namespace {

namespace fs = std::filesystem;

// Canvas and frame of the SVG, in pixels.
constexpr double kWidth = 720, kHeight = 540;
constexpr double kLeft = 80, kRight = 24, kTop = 48, kBottom = 64;
constexpr double kTickLength = 5;
constexpr double kPointRadius = 2.5;
constexpr int kCurveSamples = 200;
constexpr double kTargetTicks = 6;
constexpr double kRangePadding = 0.04;  ///< fraction of the data range added on each side
constexpr const char* kPointColour = "#1f77b4";
constexpr const char* kCurveColour = "#d62728";
/// gnuplot's PNG canvas, in pixels.
constexpr int kPngWidth = 800, kPngHeight = 600;

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

std::vector<double> curve_samples(const ScatterPlot& p, const Range& x) {
  std::vector<double> ys;
  for (int i = 0; i <= kCurveSamples; ++i)
    ys.push_back(p.curve(x.lo + (x.hi - x.lo) * i / kCurveSamples));
  return ys;
}

void svg_axes(std::ostream& out, const Frame& f, const ScatterPlot& p) {
  const double x0 = kLeft, x1 = kWidth - kRight, y0 = kHeight - kBottom, y1 = kTop;
  out << "<rect x=\"" << x0 << "\" y=\"" << y1 << "\" width=\"" << x1 - x0 << "\" height=\""
      << y0 - y1 << "\" fill=\"none\" stroke=\"black\"/>\n";
  for (double t : ticks(f.x)) {
    const std::string px = format("%.2f", f.px(t));
    out << "<line x1=\"" << px << "\" y1=\"" << y0 << "\" x2=\"" << px << "\" y2=\""
        << y0 + kTickLength << "\" stroke=\"black\"/><text x=\"" << px << "\" y=\"" << y0 + 20
        << "\" text-anchor=\"middle\">" << format("%.4g", t) << "</text>\n";
  }
  for (double t : ticks(f.y)) {
    const std::string py = format("%.2f", f.py(t));
    out << "<line x1=\"" << x0 - kTickLength << "\" y1=\"" << py << "\" x2=\"" << x0 << "\" y2=\""
        << py << "\" stroke=\"black\"/><text x=\"" << x0 - 8 << "\" y=\"" << py
        << "\" text-anchor=\"end\" dominant-baseline=\"middle\">" << format("%.4g", t)
        << "</text>\n";
  }
  out << "<text x=\"" << (x0 + x1) / 2 << "\" y=\"" << kHeight - 18 << "\" text-anchor=\"middle\">"
      << markup_escaped(p.x_label) << "</text>\n<text transform=\"translate(20," << (y0 + y1) / 2
      << ") rotate(-90)\" text-anchor=\"middle\">" << markup_escaped(p.y_label)
      << "</text>\n<text x=\"" << kWidth / 2
      << "\" y=\"28\" text-anchor=\"middle\" font-weight=\"bold\">" << markup_escaped(p.title)
      << "</text>\n";
}

void svg_data(std::ostream& out, const Frame& f, const ScatterPlot& p,
              const std::vector<double>& curve) {
  out << "<g fill=\"" << kPointColour << "\" fill-opacity=\"0.5\">\n";
  for (std::size_t i = 0; i < p.x.size(); ++i) {
    out << "<circle cx=\"" << format("%.2f", f.px(p.x[i])) << "\" cy=\""
        << format("%.2f", f.py(p.y[i])) << "\" r=\"" << kPointRadius << "\"/>\n";
  }
  out << "</g>\n<polyline fill=\"none\" stroke=\"" << kCurveColour
      << "\" stroke-width=\"2\" points=\"";
  for (int i = 0; i <= kCurveSamples; ++i) {
    const double x = f.x.lo + (f.x.hi - f.x.lo) * i / kCurveSamples;
    out << (i ? " " : "") << format("%.2f", f.px(x)) << "," << format("%.2f", f.py(curve[i]));
  }
  out << "\"/>\n";
}

std::string svg_document(const ScatterPlot& p) {
  Frame f;
  f.x = padded_range(p.x);
  const std::vector<double> curve = curve_samples(p, f.x);
  std::vector<double> all_y = p.y;
  all_y.insert(all_y.end(), curve.begin(), curve.end());
  f.y = padded_range(all_y);
  std::ostringstream out;
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" "
      << "width=\"" << kWidth << "\" height=\"" << kHeight << "\" viewBox=\"0 0 " << kWidth << " "
      << kHeight << "\" font-family=\"sans-serif\" font-size=\"13\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  svg_axes(out, f, p);
  svg_data(out, f, p, curve);
  out << "</svg>\n";
  return out.str();
}

// ---- PNG through gnuplot -------------------------------------------------------------------

std::optional<fs::path> find_program(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    const fs::path candidate = fs::path(dir.empty() ? "." : dir) / name;
    std::error_code ec;
    if (fs::is_regular_file(candidate, ec) && ::access(candidate.c_str(), X_OK) == 0) {
      return candidate;
    }
  }
  return std::nullopt;
}

// A gnuplot string literal in single quotes ('' stands for one quote).
std::string gnuplot_quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::string gnuplot_script(const ScatterPlot& p, const fs::path& output) {
  std::ostringstream s;
  s.precision(17);
  s << "set terminal pngcairo size " << kPngWidth << "," << kPngHeight << "\n"
    << "set output " << gnuplot_quoted(output.string()) << "\n"
    << "set title " << gnuplot_quoted(p.title) << " noenhanced\n"
    << "set xlabel " << gnuplot_quoted(p.x_label) << " noenhanced\n"
    << "set ylabel " << gnuplot_quoted(p.y_label) << " noenhanced\n"
    << "set key off\nset grid\n"
    << "$points << EOD\n";
  for (std::size_t i = 0; i < p.x.size(); ++i) s << p.x[i] << " " << p.y[i] << "\n";
  // The mapping as sampled points (any mapping, drawn as the SVG draws it).
  const Range x = padded_range(p.x);
  const std::vector<double> ys = curve_samples(p, x);
  s << "EOD\n$curve << EOD\n";
  for (int i = 0; i <= kCurveSamples; ++i) {
    s << x.lo + (x.hi - x.lo) * i / kCurveSamples << " " << ys[static_cast<std::size_t>(i)] << "\n";
  }
  s << "EOD\nplot $points using 1:2 with points pt 7 ps 0.6 lc rgb '" << kPointColour
    << "', $curve using 1:2 with lines lw 2 lc rgb '" << kCurveColour << "'\nset output\n";
  return s.str();
}

// Runs `program script` and waits; returns its exit status (-1 when it could not start).
int run_program(const fs::path& program, const fs::path& script) {
  std::string arg0 = program.string(), arg1 = script.string();
  char* argv[] = {arg0.data(), arg1.data(), nullptr};
  pid_t pid = 0;
  if (posix_spawn(&pid, program.c_str(), nullptr, nullptr, argv, environ) != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// A new folder in the system's temporary directory, removed with everything in it.
class PrivateDir {
 public:
  explicit PrivateDir(const fs::path& for_output) {
    std::string pattern = (fs::temp_directory_path() / "qm3d-plot-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) {
      throw InputError(for_output.string() + ": cannot create a temporary folder for gnuplot (" +
                       std::strerror(errno) + ")");
    }
    path_ = pattern;
  }
  PrivateDir(const PrivateDir&) = delete;
  PrivateDir& operator=(const PrivateDir&) = delete;
  ~PrivateDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

void write_png(const fs::path& path, const ScatterPlot& p) {
  const auto gnuplot = find_program("gnuplot");
  if (!gnuplot) {
    throw InputError(path.string() +
                     ": PNG plots are drawn by gnuplot, which is not installed "
                     "(Debian: apt-get install gnuplot-nox); or write an .svg plot");
  }
  // gnuplot draws into a folder of our own (no name another program can guess or redirect); the
  // image then goes to `path` as every other output does (a FIFO or symlink stays one).
  const PrivateDir dir(path);
  const fs::path image = dir.path() / "plot.png";
  const fs::path script = dir.path() / "plot.gp";
  write_file_atomically(script, [&](std::ostream& out) { out << gnuplot_script(p, image); });
  const int status = run_program(*gnuplot, script);
  std::error_code ec;
  if (status != 0 || !fs::is_regular_file(image, ec) || fs::file_size(image, ec) == 0) {
    throw InputError(path.string() + ": gnuplot (" + gnuplot->string() +
                     ") failed to draw the plot (exit status " + std::to_string(status) + ")");
  }
  const std::string png = read_file_bytes(image);
  write_file_atomically(path, [&](std::ostream& out) { out << png; });
}

}  // namespace

void write_auc_plot(const fs::path& path, const AucPlot& p) {
  const std::size_t n = p.names.size();
  if (n == 0 || p.auc_ds.size() != n || p.auc_bw.size() != n || p.se_ds.size() != n ||
      p.se_bw.size() != n) {
    throw std::invalid_argument("AUC plot: no metric, or values of different lengths");
  }
  const double x0 = kLeft, x1 = kWidth - kRight, y0 = kHeight - kBottom, y1 = kTop;
  const auto py = [&](double auc) {
    return y0 - (std::clamp(auc, 0.5, 1.0) - 0.5) / 0.5 * (y0 - y1);
  };
  const double slot = (x1 - x0) / static_cast<double>(n), bar = slot * 0.3;
  std::ostringstream out;
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" "
      << "width=\"" << kWidth << "\" height=\"" << kHeight << "\" viewBox=\"0 0 " << kWidth << " "
      << kHeight << "\" font-family=\"sans-serif\" font-size=\"13\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<rect x=\"" << x0 << "\" y=\"" << y1 << "\" width=\"" << x1 - x0 << "\" height=\""
      << y0 - y1 << "\" fill=\"none\" stroke=\"black\"/>\n";
  for (int k = 0; k <= 5; ++k) {
    const double v = 0.5 + 0.1 * k;
    const std::string y = format("%.2f", py(v));
    out << "<line x1=\"" << x0 - kTickLength << "\" y1=\"" << y << "\" x2=\"" << x1 << "\" y2=\""
        << y << "\" stroke=\"#ddd\"/><text x=\"" << x0 - 8 << "\" y=\"" << y
        << "\" text-anchor=\"end\" dominant-baseline=\"middle\">" << format("%.1f", v)
        << "</text>\n";
  }
  const char* colours[2] = {kPointColour, kCurveColour};
  for (std::size_t m = 0; m < n; ++m) {
    const double centre = x0 + slot * (static_cast<double>(m) + 0.5);
    const double values[2] = {p.auc_ds[m], p.auc_bw[m]}, errors[2] = {p.se_ds[m], p.se_bw[m]};
    for (int b = 0; b < 2; ++b) {
      if (!std::isfinite(values[b])) continue;
      const double left = centre + (b == 0 ? -bar : 0.0), top = py(values[b]);
      out << "<rect x=\"" << format("%.2f", left) << "\" y=\"" << format("%.2f", top)
          << "\" width=\"" << format("%.2f", bar * 0.95) << "\" height=\"" << format("%.2f", y0 - top)
          << "\" fill=\"" << colours[b] << "\" fill-opacity=\"0.7\"/>\n";
      const double mid = left + bar * 0.475, lo = py(values[b] - 1.96 * errors[b]),
                   hi = py(values[b] + 1.96 * errors[b]);
      out << "<line x1=\"" << format("%.2f", mid) << "\" y1=\"" << format("%.2f", lo) << "\" x2=\""
          << format("%.2f", mid) << "\" y2=\"" << format("%.2f", hi) << "\" stroke=\"black\"/>\n";
    }
    out << "<text x=\"" << format("%.2f", centre) << "\" y=\"" << y0 + 20
        << "\" text-anchor=\"middle\">" << markup_escaped(p.names[m]) << "</text>\n";
  }
  out << "<text transform=\"translate(20," << (y0 + y1) / 2
      << ") rotate(-90)\" text-anchor=\"middle\">AUC (0.5 = chance)</text>\n"
      << "<text x=\"" << kWidth / 2 << "\" y=\"28\" text-anchor=\"middle\" font-weight=\"bold\">"
      << markup_escaped(p.title) << "</text>\n"
      << "<text x=\"" << x1 - 4 << "\" y=\"" << kHeight - 18 << "\" text-anchor=\"end\"><tspan fill=\""
      << kPointColour << "\">&#9632; AUC_DS (different vs similar)</tspan>  <tspan fill=\""
      << kCurveColour << "\">&#9632; AUC_BW (better vs worse)</tspan>; bars: 95 % DeLong intervals</text>\n"
      << "</svg>\n";
  const std::string svg = out.str();
  write_file_atomically(path, [&](std::ostream& o) { o << svg; });
}

void write_scatter_plot(const fs::path& path, const ScatterPlot& plot) {
  if (plot.x.empty() || plot.x.size() != plot.y.size()) {
    throw std::invalid_argument("scatter plot: no points, or x and y of different lengths");
  }
  const std::string ext = lower_extension(path);
  if (ext == "svg") {
    const std::string svg = svg_document(plot);
    write_file_atomically(path, [&](std::ostream& out) { out << svg; });
  } else if (ext == "png") {
    write_png(path, plot);
  } else {
    throw InputError(path.string() + ": unknown plot format \"" + ext + "\" (use .svg or .png)");
  }
}

}  // namespace qm3d::app
