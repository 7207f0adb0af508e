#include "qm3d/report/html_report.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "markup.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/result_io.h"
#include "qm3d/common/version.h"
#include "qm3d/render/ibsm.h"
#include "report_templates.h"  // generated from report_template.html / report_index_template.html

#ifndef QM3D_THREE_JS_DEFAULT
#define QM3D_THREE_JS_DEFAULT "/usr/share/javascript/three/three.min.js"
#endif

#if !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "the report's binary blobs are written in host order, which must be little-endian"
#endif

namespace qm3d::report {
namespace {

using nlohmann::json;

// ---- command line ----

constexpr const char* kThreeJsHelp =
    "three.js (three.min.js) to inline into the report (default: $QM3D_THREE_JS, "
    "else " QM3D_THREE_JS_DEFAULT " from Debian's libjs-three)";

// ---- the page: template markers and their replacements ----

// Writes `page` to `out`, replacing each "@@NAME@@" marker (NAME: capitals and '_') by what
// `fill(NAME, out)` writes.
template <class Fill>
void fill_template(std::ostream& out, const std::string& page, const Fill& fill) {
  const auto is_name = [](const std::string& s) {
    return !s.empty() && std::all_of(s.begin(), s.end(),
                                     [](char c) { return (c >= 'A' && c <= 'Z') || c == '_'; });
  };
  std::size_t pos = 0, from = 0;
  while (true) {
    const std::size_t open = page.find("@@", from);
    const std::size_t close = open == std::string::npos ? open : page.find("@@", open + 2);
    if (close == std::string::npos) break;
    const std::string name = page.substr(open + 2, close - open - 2);
    if (!is_name(name)) {
      from = open + 2;
      continue;
    }
    out.write(page.data() + pos, static_cast<std::streamsize>(open - pos));
    fill(name, out);
    pos = from = close + 2;
  }
  out.write(page.data() + pos, static_cast<std::streamsize>(page.size() - pos));
}

// JSON inside <script>: no '<' at all (it can only be inside strings, where \u003c is the same),
// so neither "</script>" nor "<!--" can end or confuse the element.
std::string script_json(const json& j) {
  const std::string text = j.dump(-1, ' ', false, json::error_handler_t::replace);
  std::string out;
  out.reserve(text.size());
  for (char c : text) out += c == '<' ? std::string("\\u003c") : std::string(1, c);
  return out;
}

// ---- geometry ----

// One object as a view shows it: a mesh (with triangles) or points, with the elements kept under
// the display budget.
struct Shape {
  std::string object;  // "reference" / "distorted"
  Input::Kind kind = Input::Kind::kCloud;
  const std::vector<Vec3>* positions = nullptr;
  const std::vector<Rgb>* colors = nullptr;          // nullptr: none
  const std::vector<Triangle>* triangles = nullptr;  // nullptr: points
  std::vector<std::uint32_t> kept;                   // elements shown (decimated points)
  bool as_points = false;                            // a mesh over the budget, shown as points
  std::string note;                                  // what was decimated, for the page
};

Shape make_shape(const Input& input, Input::Kind as, const std::string& object,
                 std::size_t budget) {
  Shape s;
  s.object = object;
  s.kind = as;
  if (as == Input::Kind::kMesh) {
    const MeshData& m = input.mesh();
    s.positions = &m.mesh.positions;
    if (m.has_colors && m.mesh.colors.size() == m.mesh.positions.size()) s.colors = &m.mesh.colors;
    s.triangles = &m.mesh.triangles;
  } else {
    const ColoredCloud& c = input.cloud();
    s.positions = &c.positions;
    if (c.colors.size() == c.positions.size()) s.colors = &c.colors;
  }
  const std::size_t n = s.positions->size();
  if (s.triangles && s.triangles->size() > budget) {
    s.as_points = true;
    s.kept = display_subset(n, budget);
    s.note = "the " + object + " mesh has " + std::to_string(s.triangles->size()) +
             " faces, more than the display budget of " + std::to_string(budget) + ": shown as " +
             std::to_string(s.kept.size()) + " of its " + std::to_string(n) + " vertices";
  } else if (!s.triangles && n > budget) {
    s.kept = display_subset(n, budget);
    s.note = "the " + object + " cloud has " + std::to_string(n) +
             " points, more than the display budget of " + std::to_string(budget) + ": shown as " +
             std::to_string(s.kept.size()) + " of them (every " +
             std::to_string((n + budget - 1) / budget) + "th)";
  }
  return s;
}

bool decimated(const Shape& s) { return !s.kept.empty(); }

// Base64 blobs, numbered in the order they are added.
class Blobs {
 public:
  template <class T>
  int add(const std::vector<T>& v) {
    blobs_.push_back(base64(v.data(), v.size() * sizeof(T)));
    return static_cast<int>(blobs_.size()) - 1;
  }
  void write(std::ostream& out) const {
    for (std::size_t i = 0; i < blobs_.size(); ++i) {
      out << "<script type=\"application/octet-stream\" id=\"qm3d-blob-" << i << "\">";
      out << blobs_[i] << "</script>\n";
    }
  }

 private:
  std::vector<std::string> blobs_;
};

// The element indices a shape shows: its kept subset, or all of them.
template <class Fn>
void for_shown(const Shape& s, const Fn& fn) {
  if (decimated(s)) {
    for (std::uint32_t i : s.kept) fn(i);
  } else {
    for (std::size_t i = 0; i < s.positions->size(); ++i) fn(i);
  }
}

json shape_json(const Shape& s, Blobs& blobs) {
  std::vector<float> xyz;
  std::vector<std::uint8_t> rgb;
  for_shown(s, [&](std::size_t i) {
    for (double c : (*s.positions)[i]) xyz.push_back(static_cast<float>(c));
    if (!s.colors) return;
    const Rgb& c = (*s.colors)[i];
    for (double v : {c.r, c.g, c.b}) {
      rgb.push_back(static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)));
    }
  });
  json j = {{"object", s.object},
            {"kind", s.kind == Input::Kind::kMesh ? "mesh" : "cloud"},
            {"draw", s.triangles && !s.as_points ? "triangles" : "points"},
            {"elements", s.positions->size()},
            {"shown", xyz.size() / 3},
            {"positions", blobs.add(xyz)},
            {"colors", s.colors ? json(blobs.add(rgb)) : json(nullptr)},
            {"note", s.note}};
  if (s.triangles) {
    j["faces"] = s.triangles->size();
    if (!s.as_points) {
      std::vector<std::uint32_t> idx;
      idx.reserve(s.triangles->size() * 3);
      for (const Triangle& t : *s.triangles) idx.insert(idx.end(), t.begin(), t.end());
      j["indices"] = blobs.add(idx);
    }
  }
  return j;
}

// ---- heat-map layers ----

double longest_side(const std::vector<Vec3>& p) {
  return p.empty() ? 0.0 : bounding_box(p).longest_side();
}

json layer_json(const ReportEntry& e, Direction dir, const DirectionResult& d, int geometry,
                const Shape& shape, Blobs& blobs) {
  if (d.per_element.size() != shape.positions->size()) {
    throw std::logic_error("report: " + e.spec->name + " has " +
                           std::to_string(d.per_element.size()) + " per-element values for " +
                           std::to_string(shape.positions->size()) + " elements of the " +
                           shape.object);
  }
  // Rounding noise is no distortion: an identical pair's +-1e-17 is a flat map of zeros.
  const std::vector<double> v = without_noise(d.per_element, longest_side(*shape.positions));
  std::vector<float> shown;
  for_shown(shape, [&](std::size_t i) { shown.push_back(static_cast<float>(v[i])); });
  const Histogram h = histogram(v, kHistogramBins);
  double sum = 0;
  std::size_t finite = 0;
  for (double x : v) {
    if (std::isfinite(x)) sum += x, ++finite;
  }
  json regions = json::array();
  const double radius = kRegionRadiusRel * longest_side(*shape.positions);
  for (const HotRegion& r : hottest_regions(*shape.positions, v, kTopRegions, radius)) {
    regions.push_back({{"element", r.element},
                       {"x", r.center[0]},
                       {"y", r.center[1]},
                       {"z", r.center[2]},
                       {"value", r.value},
                       {"elements", r.elements},
                       {"mean", r.mean}});
  }
  return {{"metric", e.spec->name},
          {"title", e.spec->title},
          {"direction", direction_name(dir)},
          {"on", shape.object},
          {"geometry", geometry},
          {"values", blobs.add(shown)},
          {"min", h.lo},
          {"max", h.hi},
          {"mean", finite ? sum / static_cast<double>(finite) : 0.0},
          {"finite", finite},
          {"histogram", h.counts},
          {"flat", finite > 0 && h.lo == 0 && h.hi == 0},
          {"clip_percentile", kClipPercentile},
          {"clip_value", percentile(v, kClipPercentile)},
          {"region_radius", radius},
          {"regions", regions}};
}

// The shapes of the report: [0] reference, [1] distorted as read, then the other readings the
// heat-map layers need (a mesh's vertices as a cloud, for PCQM on meshes).
class Shapes {
 public:
  Shapes(const Input& ref, const Input& dist, std::size_t budget)
      : ref_(ref), dist_(dist), budget_(budget) {
    index(true, ref.kind());
    index(false, dist.kind());
  }
  int index(bool reference, Input::Kind kind) {
    for (std::size_t i = 0; i < shapes_.size(); ++i) {
      if (std::find(own_.begin(), own_.end(), i) != own_.end()) continue;
      if (keys_[i] == std::make_pair(reference, kind)) return static_cast<int>(i);
    }
    shapes_.push_back(
        make_shape(reference ? ref_ : dist_, kind, reference ? "reference" : "distorted", budget_));
    keys_.emplace_back(reference, kind);
    return static_cast<int>(shapes_.size()) - 1;
  }
  // Points of their own (a metric's per-element positions: GeodesicPSIM's keypoints).
  int points(const std::vector<Vec3>& positions, const std::string& object) {
    Shape s;
    s.object = object;
    s.positions = &positions;
    if (positions.size() > budget_) s.kept = display_subset(positions.size(), budget_);
    shapes_.push_back(std::move(s));
    keys_.emplace_back(false, Input::Kind::kMesh);  // never looked up: points() adds each time
    own_.push_back(shapes_.size() - 1);
    return static_cast<int>(shapes_.size()) - 1;
  }
  const Shape& operator[](int i) const { return shapes_[static_cast<std::size_t>(i)]; }
  std::size_t size() const { return shapes_.size(); }
  Input::Kind reads(const MetricSpec& spec) const { return spec.reads_for(ref_, dist_); }
  bool per_element_on_inputs(const MetricSpec& spec) const {
    return spec.per_element_on_inputs(ref_, dist_);
  }

 private:
  const Input& ref_;
  const Input& dist_;
  std::size_t budget_;
  std::vector<Shape> shapes_;
  std::vector<std::pair<bool, Input::Kind>> keys_;
  std::vector<std::size_t> own_;  // shapes made by points()
};

// The layers of a metric whose per-element values sit at positions of their own (GeodesicPSIM's
// keypoints on the reference), drawn as points.
void element_position_layers(const ReportEntry& e, Shapes& shapes, Blobs& blobs, json& layers) {
  const std::pair<Direction, const std::optional<DirectionResult>*> dirs[2] = {
      {Direction::kRefToDist, &e.result->ref_to_dist},
      {Direction::kDistToRef, &e.result->dist_to_ref}};
  for (const auto& [dir, d] : dirs) {
    if (!d->has_value() || (*d)->per_element.empty() || (*d)->element_positions.empty()) continue;
    const std::string on = dir == Direction::kRefToDist ? "reference" : "distorted";
    const int g = shapes.points((*d)->element_positions, e.spec->name + " points on the " + on);
    layers.push_back(layer_json(e, dir, **d, g, shapes[g], blobs));
  }
}

// Every direction of every metric with per-element values on its inputs, each metric's
// preferred direction first (the one --map writes).
json layers_json(const std::vector<ReportEntry>& entries, Shapes& shapes, Blobs& blobs) {
  json layers = json::array();
  for (const ReportEntry& e : entries) {
    if (!shapes.per_element_on_inputs(*e.spec)) {
      if (e.spec->per_element_positions) element_position_layers(e, shapes, blobs, layers);
      continue;
    }
    const bool prefer_dist = e.spec->default_direction != Direction::kRefToDist;
    const std::pair<Direction, const std::optional<DirectionResult>*> dirs[2] = {
        {Direction::kDistToRef, &e.result->dist_to_ref},
        {Direction::kRefToDist, &e.result->ref_to_dist}};
    for (int k = 0; k < 2; ++k) {
      const auto& [dir, d] = dirs[prefer_dist ? k : 1 - k];
      if (!d->has_value() || (*d)->per_element.empty()) continue;
      if (e.result->details.contains("keypoint_rows")) continue;  // on keypoints, not elements
      const int g = shapes.index(dir == Direction::kRefToDist, shapes.reads(*e.spec));
      layers.push_back(layer_json(e, dir, **d, g, shapes[g], blobs));
    }
  }
  return layers;
}

json metrics_json(const std::vector<ReportEntry>& entries, const Shapes& shapes) {
  json metrics = json::array();
  for (const ReportEntry& e : entries) {
    json m = to_json(*e.result);
    m["title"] = e.spec->title;
    // f1..f8 metrics name their features; the others (psnr, ibsm) their named values.
    json names = e.result->feature_names;
    if (e.result->feature_names.empty()) {
      for (const auto& [name, value] : e.result->values) names.push_back(name);
    }
    m["feature_names"] = names;
    m["per_element_on_input"] = shapes.per_element_on_inputs(*e.spec);
    m["higher_is_better"] = e.spec->higher_is_better;
    m["symmetric_rule"] = e.spec->symmetric_rule;
    metrics.push_back(std::move(m));
  }
  return metrics;
}

/// The view pairs of the image metrics that ran (ibsm), rendered again at up to
/// kReportViewPixels for the page, as base64 PNG.
json rendered_views_json(const std::vector<ReportEntry>& entries, const Input& ref,
                         const Input& dist) {
  json sets = json::array();
  for (const ReportEntry& e : entries) {
    if (e.spec->name != "ibsm" || !e.result->details.contains("render")) continue;
    const int scored = e.result->details.at("render").at("resolution").get<int>();
    const int shown = std::min(scored, kReportViewPixels);
    const std::vector<render::ViewPair> pairs = render::result_view_pairs(*e.result, ref, dist, shown);
    json views = json::array();
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      const json& scored_view = e.result->details.at("views").at(i);
      const std::vector<std::uint8_t> a = render::png_bytes(pairs[i].reference);
      const std::vector<std::uint8_t> b = render::png_bytes(pairs[i].distorted);
      views.push_back({{"direction", scored_view.at("direction")},
                       {"left_out", scored_view.at("left_out")},
                       {"yuv_psnr", scored_view.at("yuv_psnr")},
                       {"ssim", scored_view.at("ssim")},
                       {"reference", base64(a.data(), a.size())},
                       {"distorted", base64(b.data(), b.size())}});
    }
    sets.push_back({{"metric", e.spec->name},
                    {"title", e.spec->title},
                    {"resolution", shown},
                    {"scored_resolution", scored},
                    {"views", views}});
  }
  return sets;
}

json report_json(const std::vector<ReportEntry>& entries, const Input& ref, const Input& dist,
                 const ReportSettings& settings, Blobs& blobs) {
  Shapes shapes(ref, dist, settings.display_budget);
  json layers = layers_json(entries, shapes, blobs);
  json geometries = json::array(), notes = json::array();
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    geometries.push_back(shape_json(shapes[static_cast<int>(i)], blobs));
    if (!shapes[static_cast<int>(i)].note.empty())
      notes.push_back(shapes[static_cast<int>(i)].note);
  }
  json j = {{"version", kVersion},
            {"reference", ref.name()},
            {"distorted", dist.name()},
            {"metrics", metrics_json(entries, shapes)},
            {"geometries", geometries},
            {"layers", layers},
            {"display_budget", settings.display_budget},
            {"notes", notes},
            {"colormap", "blue-cyan-green-yellow-red (as the --map PLY's colours)"}};
  j["range"] = settings.fixed_range ? json(*settings.fixed_range) : json(nullptr);
  j["rendered_views"] = rendered_views_json(entries, ref, dist);
  return j;
}

InputError three_js_missing(const std::filesystem::path& path) {
  return InputError(path.string() +
                    ": three.js not found (install Debian's libjs-three, or give --three-js FILE "
                    "or set QM3D_THREE_JS)");
}

std::string three_js_text(const std::filesystem::path& path) {
  if (!std::filesystem::is_regular_file(path)) throw three_js_missing(path);
  // three.js's minified build is ~1 MB; the limit only keeps a wrong path from filling memory.
  constexpr std::uintmax_t kMaxThreeJsBytes = std::uintmax_t(64) << 20;
  std::string text = read_file_bytes(path, kMaxThreeJsBytes);
  // Inside <script>, "</script" would end the element; a JS string or regex may spell it "<\/".
  for (std::size_t p = text.find("</script"); p != std::string::npos;
       p = text.find("</script", p + 2)) {
    text.replace(p, 2, "<\\/");
  }
  return text;
}

std::string sanitized_stem(const std::string& path) {
  std::string stem = std::filesystem::path(path).stem().string(), out;
  for (char c : stem) {
    const bool ok = std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.';
    out += ok ? c : '_';
  }
  constexpr std::size_t kMaxStem = 60;
  return out.substr(0, kMaxStem);
}

}  // namespace

// ---- command line ----

namespace {

void add_drawing_options(CLI::App* cmd, ReportCli& cli) {
  cmd->add_option("--three-js", cli.three_js, kThreeJsHelp)->type_name("FILE");
  cmd->add_option("--range", cli.range,
                  "Fixed colour range of the report's heat map (the page switches between it and "
                  "each object's own min..max; default: per object)")
      ->type_name("LO,HI");
}

}  // namespace

void add_report_dir_options(CLI::App* cmd, ReportCli& cli, const std::string& help) {
  cmd->add_option("--report-dir", cli.file, help)->type_name("DIR");
  add_drawing_options(cmd, cli);
}

void add_report_options(CLI::App* cmd, ReportCli& cli, bool as_command) {
  if (as_command) {
    cmd->add_option("-o,--output", cli.file,
                    "The report: one self-contained HTML file (opens offline in any browser)")
        ->required()
        ->type_name("FILE.html");
  } else {
    cmd->add_option("--report", cli.file,
                    "Also write an HTML report: scores, features, options, warnings, linked 3-D "
                    "views of both objects and the local-distortion heat map, its histogram and "
                    "hottest regions (one self-contained file that opens offline)")
        ->type_name("FILE.html");
  }
  add_drawing_options(cmd, cli);
}

std::filesystem::path resolve_three_js(const std::string& option) {
  std::filesystem::path path = option;
  if (path.empty()) {
    const char* env = std::getenv("QM3D_THREE_JS");
    path = env && *env ? env : QM3D_THREE_JS_DEFAULT;
  }
  if (!std::filesystem::is_regular_file(path)) throw three_js_missing(path);
  return path;
}

std::array<double, 2> parse_range(const std::string& text) {
  const auto bad = [&](const std::string& why) {
    return std::invalid_argument("--range: '" + text + "' " + why);
  };
  const std::size_t comma = text.find(',');
  if (comma == std::string::npos) throw bad("is not LO,HI");
  std::array<double, 2> r{};
  const std::string parts[2] = {text.substr(0, comma), text.substr(comma + 1)};
  for (int i = 0; i < 2; ++i) {
    std::size_t used = 0;
    try {
      r[i] = std::stod(parts[i], &used);
    } catch (const std::logic_error&) {
      throw bad("is not LO,HI (two numbers)");
    }
    if (used != parts[i].size() || !std::isfinite(r[i])) throw bad("is not LO,HI (two numbers)");
  }
  if (!(r[0] < r[1])) throw bad("needs LO < HI");
  return r;
}

ReportSettings report_settings(const ReportCli& cli) {
  ReportSettings s;
  s.three_js = resolve_three_js(cli.three_js);
  if (!cli.range.empty()) s.fixed_range = parse_range(cli.range);
  return s;
}

// ---- the report ----

void write_html_report(const std::filesystem::path& file, const std::vector<ReportEntry>& entries,
                       const Input& reference, const Input& distorted,
                       const ReportSettings& settings) {
  const std::string three = three_js_text(settings.three_js);
  Blobs blobs;
  const json data = report_json(entries, reference, distorted, settings, blobs);
  const std::string title =
      "qm3d report: " + std::filesystem::path(distorted.name()).filename().string() + " vs " +
      std::filesystem::path(reference.name()).filename().string();
  write_file_atomically(file, [&](std::ostream& out) {
    fill_template(out, kReportTemplate, [&](const std::string& marker, std::ostream& o) {
      if (marker == "TITLE") {
        o << markup_escaped(title);
      } else if (marker == "THREE_JS") {
        o << "/* three.js (MIT licence, https://threejs.org), inlined by qm3d from "
          << markup_escaped(settings.three_js.string()) << " */\n"
          << three;
      } else if (marker == "DATA") {
        o << script_json(data);
      } else if (marker == "BLOBS") {
        blobs.write(o);
      } else {
        throw std::logic_error("report template: unknown marker @@" + marker + "@@");
      }
    });
  });
}

// ---- the batch index ----

namespace {

struct IndexPair {
  std::string reference, distorted, report, error;
  std::map<std::string, std::optional<double>> scores;
};

/// A metric column of the index: its name and whether higher scores are better.
struct IndexColumn {
  std::string metric;
  bool higher_is_better = false;
  double lo = HUGE_VAL, hi = -HUGE_VAL;  ///< range of the finite scores
};

std::vector<IndexPair> group_pairs(const std::vector<IndexRow>& rows,
                                   std::vector<IndexColumn>& columns) {
  std::vector<IndexPair> pairs;
  std::map<std::pair<std::string, std::string>, std::size_t> at;
  for (const IndexRow& r : rows) {
    auto c = std::find_if(columns.begin(), columns.end(),
                          [&](const IndexColumn& k) { return k.metric == r.metric; });
    if (c == columns.end() && r.score) {
      columns.push_back({r.metric, r.higher_is_better});
      c = columns.end() - 1;
    }
    if (c != columns.end() && r.score && std::isfinite(*r.score)) {
      c->lo = std::min(c->lo, *r.score);
      c->hi = std::max(c->hi, *r.score);
    }
    const auto [it, added] = at.emplace(std::make_pair(r.reference, r.distorted), pairs.size());
    if (added) pairs.push_back({r.reference, r.distorted, r.report, "", {}});
    IndexPair& p = pairs[it->second];
    p.scores[r.metric] = r.score;
    if (!r.error.empty()) p.error += (p.error.empty() ? "" : "; ") + r.metric + ": " + r.error;
    if (p.report.empty()) p.report = r.report;
  }
  return pairs;
}

// How distorted a score is: larger = worse, whatever the metric's orientation (a quality's +inf,
// identical inputs, is the least distorted).
double badness(const IndexColumn& c, double v) { return c.higher_is_better ? -v : v; }

// Most distorted pair of the first column first; pairs without it after, failed pairs last.
void sort_pairs(std::vector<IndexPair>& pairs, const std::vector<IndexColumn>& columns) {
  const auto key = [&](const IndexPair& p) {
    for (const IndexColumn& c : columns) {
      const auto it = p.scores.find(c.metric);
      if (it != p.scores.end() && it->second && !std::isnan(*it->second)) {
        return std::make_pair(&c == &columns.front() ? 0 : 1, -badness(c, *it->second));
      }
    }
    return std::make_pair(2, 0.0);
  };
  std::stable_sort(pairs.begin(), pairs.end(),
                   [&](const IndexPair& a, const IndexPair& b) { return key(a) < key(b); });
}

// A number as JavaScript's parseFloat reads it (inf as "Infinity").
std::string js_number(double v) {
  if (std::isinf(v)) return v > 0 ? "Infinity" : "-Infinity";
  return format_double(v);
}

// A score as people read it: 6 significant digits (the full value is the cell's data-value).
std::string score_text(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

// The cell's tint: transparent for the least distorted pair of the column, strongest red for
// the most distorted.
std::string tint(const IndexColumn& c, double v) {
  if (!(c.hi > c.lo)) return "";
  double t = std::isfinite(v) ? (v - c.lo) / (c.hi - c.lo) : (v > 0 ? 1.0 : 0.0);
  if (c.higher_is_better) t = 1 - t;
  char style[64];
  std::snprintf(style, sizeof style, " style=\"background:rgba(215,48,39,%.2f)\"", 0.45 * t);
  return style;
}

std::string index_rows_html(const std::vector<IndexPair>& pairs,
                            const std::vector<IndexColumn>& columns) {
  std::ostringstream o;
  o << "<thead><tr><th data-type=\"text\">distorted</th><th data-type=\"text\">reference</th>";
  for (const auto& c : columns) {
    o << "<th data-type=\"number\" data-worse=\"" << (c.higher_is_better ? "lower" : "higher")
      << "\" title=\"" << (c.higher_is_better ? "a quality: higher is better" : "a distortion: "
                                                                          "lower is better")
      << "\">" << markup_escaped(c.metric) << "</th>";
  }
  o << "<th data-type=\"text\">report</th></tr></thead>\n<tbody>\n";
  for (const IndexPair& p : pairs) {
    o << "<tr" << (p.error.empty() ? "" : " class=\"failed\"") << "><td>"
      << markup_escaped(p.distorted) << "</td><td>" << markup_escaped(p.reference) << "</td>";
    for (const auto& c : columns) {
      const auto it = p.scores.find(c.metric);
      const bool has = it != p.scores.end() && it->second;
      o << "<td class=\"num\" data-value=\"" << (has ? js_number(*it->second) : "") << "\""
        << (has ? tint(c, *it->second) : "") << ">" << (has ? score_text(*it->second) : "")
        << "</td>";
    }
    o << "<td>";
    if (!p.report.empty()) o << "<a href=\"" << markup_escaped(p.report) << "\">report</a>";
    if (!p.error.empty()) o << "<span class=\"error\">" << markup_escaped(p.error) << "</span>";
    o << "</td></tr>\n";
  }
  o << "</tbody>";
  return o.str();
}

}  // namespace

void write_report_index(const std::filesystem::path& file, const std::vector<IndexRow>& rows,
                        const std::string& title) {
  std::vector<IndexColumn> columns;
  std::vector<IndexPair> pairs = group_pairs(rows, columns);
  sort_pairs(pairs, columns);
  const std::string table = index_rows_html(pairs, columns);
  std::size_t failed = 0;
  for (const IndexPair& p : pairs) failed += p.error.empty() ? 0 : 1;
  write_file_atomically(file, [&](std::ostream& out) {
    fill_template(out, kIndexTemplate, [&](const std::string& marker, std::ostream& o) {
      if (marker == "TITLE") {
        o << markup_escaped(title);
      } else if (marker == "SUMMARY") {
        o << pairs.size() << " pairs, " << failed << " failed; sorted by "
          << markup_escaped(columns.empty() ? std::string("score") : columns.front().metric)
          << ", most distorted first (click a column to sort by it; the redder a score, the "
             "more distorted the pair among the column's). qm3d "
          << kVersion;
      } else if (marker == "TABLE") {
        o << table;
      } else {
        throw std::logic_error("index template: unknown marker @@" + marker + "@@");
      }
    });
  });
}

std::string report_file_name(const std::string& reference, const std::string& distorted) {
  // FNV-1a, 64 bits, of both paths as written.
  std::uint64_t h = 14695981039346656037ull;
  for (char c : reference + '\n' + distorted) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return sanitized_stem(distorted) + "_vs_" + sanitized_stem(reference) + "-" +
         std::string(hex, 8) + ".html";
}

// ---- parts ----

std::string base64(const void* data, std::size_t bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* p = static_cast<const unsigned char*>(data);
  std::string out;
  out.reserve((bytes + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= bytes; i += 3) {
    const std::uint32_t v = (p[i] << 16) | (p[i + 1] << 8) | p[i + 2];
    for (int s : {18, 12, 6, 0}) out += kAlphabet[(v >> s) & 63];
  }
  if (i < bytes) {
    const bool two = i + 1 < bytes;
    const std::uint32_t v = (p[i] << 16) | (two ? p[i + 1] << 8 : 0);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += two ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::vector<HotRegion> hottest_regions(const std::vector<Vec3>& positions,
                                       const std::vector<double>& values, std::size_t k,
                                       double radius) {
  if (positions.size() != values.size()) {
    throw std::invalid_argument("hottest_regions: #positions != #values");
  }
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (std::isfinite(values[i])) order.push_back(i);
  }
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return values[a] != values[b] ? values[a] > values[b] : a < b;
  });
  const double r2 = radius * radius;
  const auto dist2 = [&](std::size_t a, std::size_t b) {
    double s = 0;
    for (int c = 0; c < 3; ++c)
      s += (positions[a][c] - positions[b][c]) * (positions[a][c] - positions[b][c]);
    return s;
  };
  std::vector<HotRegion> regions;
  for (std::size_t i : order) {
    if (regions.size() == k) break;
    const bool near = std::any_of(regions.begin(), regions.end(),
                                  [&](const HotRegion& r) { return dist2(i, r.element) < r2; });
    if (!near) regions.push_back({i, positions[i], values[i], 0, 0});
  }
  for (HotRegion& r : regions) {
    double sum = 0;
    for (std::size_t i : order) {  // finite values, in a fixed order
      if (dist2(i, r.element) < r2) sum += values[i], ++r.elements;
    }
    r.mean = sum / static_cast<double>(r.elements);  // the seed itself is within
  }
  return regions;
}

Histogram histogram(const std::vector<double>& values, std::size_t bins) {
  Histogram h;
  bool any = false;
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    h.lo = any ? std::min(h.lo, v) : v;
    h.hi = any ? std::max(h.hi, v) : v;
    any = true;
  }
  if (!any || bins == 0) return h;
  h.counts.assign(h.hi > h.lo ? bins : 1, 0);
  const double width = (h.hi - h.lo) / static_cast<double>(h.counts.size());
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    const std::size_t b = h.hi > h.lo ? static_cast<std::size_t>((v - h.lo) / width) : 0;
    ++h.counts[std::min(b, h.counts.size() - 1)];
  }
  return h;
}

std::vector<double> without_noise(std::vector<double> values, double size) {
  const double floor = kNoiseFloor * std::max(1.0, size);
  for (double& v : values) {
    if (std::fabs(v) < floor) v = 0;
  }
  return values;
}

double percentile(const std::vector<double>& values, double p) {
  std::vector<double> finite;
  for (double v : values) {
    if (std::isfinite(v)) finite.push_back(v);
  }
  if (finite.empty()) return 0;
  std::sort(finite.begin(), finite.end());
  // Nearest rank: the smallest value with at least p % of the values at or below it.
  const double rank = std::ceil(p / 100 * static_cast<double>(finite.size()));
  const std::size_t k = static_cast<std::size_t>(std::max(rank, 1.0)) - 1;
  return finite[std::min(k, finite.size() - 1)];
}

std::vector<std::uint32_t> display_subset(std::size_t n, std::size_t budget) {
  std::vector<std::uint32_t> kept;
  if (budget == 0) throw std::invalid_argument("display_subset: budget 0");
  const std::size_t step = n <= budget ? 1 : (n + budget - 1) / budget;
  kept.reserve(n / step + 1);
  for (std::size_t i = 0; i < n; i += step) kept.push_back(static_cast<std::uint32_t>(i));
  return kept;
}

}  // namespace qm3d::report
