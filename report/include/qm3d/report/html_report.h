// The HTML report (`qm3d report`, `--report FILE.html`, `qm3d batch --report-dir`, `qm3d demo`):
// one self-contained file that opens offline, with the scores, features, options and warnings of
// every metric that ran, three linked 3-D views (reference, distorted, local-distortion heat map)
// drawn with three.js (inlined from the Debian package libjs-three), a colour bar, a histogram of
// the local distortion and its hottest regions.
//
// The page itself (HTML, CSS, JavaScript) is report/src/report_template.html, embedded at build time;
// this file fills it with the data: a JSON description and the geometry as base64 blobs (float32
// positions, uint8 colours, uint32 triangle indices, float32 per-element values, little-endian).
#pragma once

#include <CLI/CLI.hpp>
#include <array>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "qm3d/common/metric.h"
#include "qm3d/common/result.h"
#include "qm3d/common/types.h"

namespace qm3d::report {

/// Above this many points (clouds) or faces (meshes) a view is decimated: a cloud keeps every
/// k-th point, a mesh is shown as (every k-th of) its vertices. The report says so.
constexpr std::size_t kDisplayBudget = 2'000'000;
/// Hottest regions listed under the heat map.
constexpr std::size_t kTopRegions = 10;
/// Radius of a hottest region, as a fraction of the longest bounding-box side of the object the
/// values are on: two listed regions are at least this far apart.
constexpr double kRegionRadiusRel = 0.05;
/// Bins of the local-distortion histogram.
constexpr std::size_t kHistogramBins = 64;
/// Largest side of the rendered views an image metric's section shows (re-rendered from the
/// result's cameras: 16 pairs of 384² PNGs are about 1-2 MB).
constexpr int kReportViewPixels = 384;

/// How a report is drawn.
struct ReportSettings {
  std::filesystem::path three_js;  ///< three.min.js to inline (resolve_three_js)
  /// A fixed colour range for the heat map (--range LO,HI); unset = each object's min..max. The
  /// page switches between the two either way.
  std::optional<std::array<double, 2>> fixed_range;
  std::size_t display_budget = kDisplayBudget;
};

/// The report options as typed on the command line.
struct ReportCli {
  std::string file;      ///< --report FILE.html (`qm3d report`: -o FILE.html)
  std::string three_js;  ///< --three-js FILE
  std::string range;     ///< --range LO,HI
};

/// Adds --three-js and --range, and `--report FILE.html` (or, for `qm3d report`, the required
/// `-o,--output FILE.html` when `as_command`).
void add_report_options(CLI::App* cmd, ReportCli& cli, bool as_command);
/// Adds `--report-dir DIR` (stored in cli.file; `help` says what goes there), --three-js and
/// --range (batch, demo).
void add_report_dir_options(CLI::App* cmd, ReportCli& cli, const std::string& help);

/// three.min.js: `option` when given, else $QM3D_THREE_JS, else the Debian package's file
/// (/usr/share/javascript/three/three.min.js). InputError naming the file when it is not there.
std::filesystem::path resolve_three_js(const std::string& option);
/// "LO,HI" with LO < HI, both finite; std::invalid_argument quoting `text` otherwise.
std::array<double, 2> parse_range(const std::string& text);
/// The settings of `cli` (three.js resolved, range parsed): call it before scoring, so that a
/// missing three.js fails fast.
ReportSettings report_settings(const ReportCli& cli);

/// One metric's result as the report shows it.
struct ReportEntry {
  const MetricSpec* spec = nullptr;
  const MetricResult* result = nullptr;  ///< with per-element values (RunOptions::per_element)
};

/// Writes the report of one pair atomically. `entries` in display order; the heat map offers
/// every direction of every metric whose per-element values are on its inputs (the first is the
/// one `--map` writes for the first such metric). InputError naming `file` when it cannot be
/// written or three.js cannot be read.
void write_html_report(const std::filesystem::path& file, const std::vector<ReportEntry>& entries,
                       const Input& reference, const Input& distorted,
                       const ReportSettings& settings);

/// One line of a batch's report index.
struct IndexRow {
  std::string reference, distorted, metric;
  std::optional<double> score;  ///< unset: the row failed
  std::string error;
  std::string report;  ///< the pair's report, relative to the index; empty = none
  bool higher_is_better = false;  ///< the metric's score is a quality (MetricSpec)
};

/// Writes index.html: one row per pair (its metrics as columns), sorted by the score of the first
/// metric column, most distorted first (the highest distortion, the lowest quality), failed pairs
/// last; each links to its report. Each score cell is tinted by how distorted the pair is among
/// the column's pairs (the metric's orientation decides which end is worse).
void write_report_index(const std::filesystem::path& file, const std::vector<IndexRow>& rows,
                        const std::string& title);

/// The report file name of a pair in a report folder: stems of both files and a hash of both
/// paths as written (stable across runs, shards and --resume).
std::string report_file_name(const std::string& reference, const std::string& distorted);

// ---- the parts, exposed for the tests ----

/// RFC 4648 base64 of `bytes` bytes.
std::string base64(const void* data, std::size_t bytes);

/// A hottest region: the hottest element not within `radius` of a hotter region's seed.
struct HotRegion {
  std::size_t element = 0;   ///< index of the seed element
  Vec3 center{};             ///< its position
  double value = 0;          ///< its value (the region's maximum)
  std::size_t elements = 0;  ///< elements within `radius` of the seed
  double mean = 0;           ///< their mean value
};

/// Up to `k` regions, hottest first (ties by element index); non-finite values ignored.
/// #positions == #values.
std::vector<HotRegion> hottest_regions(const std::vector<Vec3>& positions,
                                       const std::vector<double>& values, std::size_t k,
                                       double radius);

/// Counts of the finite values in `bins` equal bins over [lo, hi] = their min..max (one bin
/// holding everything when they are all equal; no bins when none is finite).
struct Histogram {
  double lo = 0, hi = 0;
  std::vector<std::size_t> counts;
};
Histogram histogram(const std::vector<double>& values, std::size_t bins);

/// Per-element values smaller in magnitude than this fraction of the scale (the object's
/// longest box side, at least 1: distances, and metrics in [0, 1]) are rounding noise, shown 0.
constexpr double kNoiseFloor = 1e-12;
/// The heat map's default colour range ends at this percentile of the values, so that a long
/// tail of a few large values does not push every other element to the low end of the colours.
constexpr double kClipPercentile = 99;

/// `values` with every value below kNoiseFloor * max(1, size) in magnitude set to 0.
std::vector<double> without_noise(std::vector<double> values, double size);

/// The nearest-rank `p`th percentile of the finite values (0 when there are none).
double percentile(const std::vector<double>& values, double p);

/// The elements a view keeps of `n` under `budget`: all when n <= budget, else every k-th
/// (k = ceil(n / budget)), starting at 0.
std::vector<std::uint32_t> display_subset(std::size_t n, std::size_t budget);

}  // namespace qm3d::report
