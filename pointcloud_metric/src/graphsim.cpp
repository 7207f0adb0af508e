// GraphSIM and MS-GraphSIM (graphsim_engine.h): the registry entries "graphsim" and
// "msgraphsim". Reproduces NJUVISION/GraphSIM @ fdd595d and zhangyujie-1998/MS_GraphSIM @ b225a59
// in float64 (the reference data's f64 columns; the MATLAB code's float32 casts are not
// reproduced). Both are similarities: 1 for a cloud against itself.
// - Keypoints: rows of the reference, from --keypoint-file (0-based row indices in file order, one
//   per line; a row given twice counts twice) or drawn by qm3d's seeded rule
//   (graphsim_keypoints.cpp; count round(N / 10000), at least 1, unless --keypoints says).
// - eps = floor(smallest side of the reference's bounding box / 10); 0 is refused.
// - Colours as the reference reads them: 8-bit values (qm3d's 0..1 colours times 255, rounded).
// - Score: the mean of the keypoints' scores s_k = sum_ch w_ch |p_ch| / sum w (in keypoint order:
//   the same bits for any thread count). MS-GraphSIM: each scale's mean, then the mean of the
//   `scales` scale means in scale order.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <sstream>
#include <string>
#include <vector>

#include "graphsim_engine.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/metric.h"
#include "qm3d/common/progress.h"
#include "qm3d/common/version.h"
#include "qm3d/pointcloud/metrics.h"

namespace qm3d::pointcloud {
namespace {

using detail::Colour255;
using detail::GraphsimCloud;
using detail::GraphsimParams;
using detail::KeypointScores;

/// The authors' keypoint script draws round(N / num) keypoints, num = 10000.
constexpr double kPointsPerKeypoint = 10000;
/// The neighbourhood radius is floor(smallest box side / kEpsDivisor).
constexpr double kEpsDivisor = 10;
/// MS-GraphSIM's code computes 6 scales (n_s picks how many are averaged).
constexpr int kMaxScales = 6;
/// More keypoints than any cloud needs (each costs two local graphs).
constexpr double kMaxKeypoints = 1e8;
constexpr std::uintmax_t kMaxKeypointFileBytes = std::uintmax_t(1) << 30;

int thread_count(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

void check_cloud(const ColoredCloud& c, const std::string& name, const std::string& metric) {
  if (c.positions.empty()) throw NumericError(name + ": the cloud is empty");
  if (c.colors.size() != c.positions.size()) {
    throw FormatError(name + ": no vertex colours (" + metric +
                      " compares colours: red/green/blue vertex properties needed)");
  }
  for (std::size_t i = 0; i < c.positions.size(); ++i) {
    for (double v : c.positions[i]) {
      if (!std::isfinite(v)) {
        throw NumericError(name + ": point " + std::to_string(i) + " has a non-finite coordinate");
      }
    }
  }
}

/// The colours as 8-bit values, as the reference reads them.
std::vector<Colour255> colours_255(const std::vector<Rgb>& colors) {
  const auto byte = [](double v) { return std::round(std::clamp(v, 0.0, 1.0) * 255.0); };
  std::vector<Colour255> out(colors.size());
  for (std::size_t i = 0; i < colors.size(); ++i) {
    out[i] = {byte(colors[i].r), byte(colors[i].g), byte(colors[i].b)};
  }
  return out;
}

double neighbourhood_radius(const std::vector<Vec3>& positions, const std::string& name) {
  const BoundingBox box = bounding_box(positions);
  const double side =
      std::min({box.max[0] - box.min[0], box.max[1] - box.min[1], box.max[2] - box.min[2]});
  const double eps = std::floor(side / kEpsDivisor);
  if (!(eps > 0)) {
    std::ostringstream o;
    o << name << ": the neighbourhood radius floor(smallest bounding-box side / 10) is 0 (side "
      << side << "): GraphSIM needs a box at least 10 units on every side (e.g. voxel coordinates)";
    throw NumericError(o.str());
  }
  return eps;
}

/// 0-based row indices, one per line (blank lines skipped), each < `rows`.
std::vector<std::size_t> read_keypoints(const std::string& file, std::size_t rows) {
  const std::string text = read_file_bytes(file, kMaxKeypointFileBytes);
  std::istringstream in(text);
  std::string line;
  std::vector<std::size_t> out;
  for (std::size_t number = 1; std::getline(in, line); ++number) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos) continue;
    const auto last = line.find_last_not_of(" \t\r");
    const std::string item = line.substr(first, last - first + 1);
    const bool digits =
        std::all_of(item.begin(), item.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
    const std::string where = file + ": line " + std::to_string(number) + ": ";
    if (!digits || item.size() > 18) {
      throw FormatError(where + "'" + item + "' is not a 0-based row index");
    }
    const std::size_t v = std::stoull(item);
    if (v >= rows) {
      throw FormatError(where + "keypoint index " + item + " is out of range (the reference has " +
                        std::to_string(rows) + " points, indices 0.." + std::to_string(rows - 1) +
                        ")");
    }
    out.push_back(v);
  }
  if (out.empty()) throw FormatError(file + ": no keypoint indices");
  return out;
}

std::vector<std::size_t> keypoints_for(const std::vector<Vec3>& ref, const OptionValues& o,
                                       int threads, std::string& rule) {
  const std::string file = o.at("keypoint_file").get<std::string>();
  if (!file.empty()) {
    rule = "file " + file;
    return read_keypoints(file, ref.size());
  }
  std::size_t count = o.at("keypoints").get<std::size_t>();
  if (count == 0) {
    count = std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(
                                         static_cast<double>(ref.size()) / kPointsPerKeypoint)));
  }
  const auto seed = o.at("seed").get<std::uint64_t>();
  rule = "variation score, seed " + std::to_string(seed);
  return detail::choose_keypoints(ref, count, seed, threads);
}

GraphsimParams params_of(const OptionValues& o, bool multiscale) {
  GraphsimParams p;
  p.threshold = o.at("threshold").get<double>();
  for (int k = 0; k < 3; ++k) p.weights[k] = o.at("pooling_weights").at(k).get<double>();
  if (!(p.weights[0] + p.weights[1] + p.weights[2] > 0)) {
    throw std::invalid_argument("pooling_weights: at least one weight must be > 0");
  }
  if (multiscale) {
    p.blur_ratio = o.at("blur_ratio").get<double>();
    p.sample_ratio = o.at("sample_ratio").get<double>();
    p.scales = o.at("scales").get<int>();
  }
  return p;
}

/// Every keypoint's scores, in keypoint order (each keypoint's own: any thread count).
std::vector<KeypointScores> score_all(const GraphsimCloud& ref, const GraphsimCloud& dist,
                                      const std::vector<std::size_t>& keys, double eps,
                                      const GraphsimParams& params, int threads,
                                      ProgressSteps& progress) {
  std::vector<KeypointScores> out(keys.size());
  std::vector<std::exception_ptr> errors(keys.size());  // no exception leaves a parallel loop
  const long n = static_cast<long>(keys.size());
  LoopProgress done(&progress, keys.size());
#pragma omp parallel for num_threads(thread_count(threads)) schedule(dynamic, 1)
  for (long k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>(k);
    try {
      out[i] = detail::score_keypoint(ref, dist, keys[i], eps, params);
    } catch (...) {
      errors[i] = std::current_exception();
    }
    done.add();
  }
  done.finish();
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  return out;
}

/// The result of the keypoints' scores: per-scale means (in keypoint order), the score, the
/// per-keypoint values (per_element: in keypoint order, the keypoint's mean over the scales).
DirectionResult direction_of(const std::vector<KeypointScores>& scores, bool multiscale, int scales,
                             bool per_element) {
  const double n = static_cast<double>(scores.size());
  std::vector<double> means(static_cast<std::size_t>(scales), 0.0);
  std::array<double, 3> channels{0, 0, 0};
  for (const KeypointScores& s : scores) {
    for (int k = 0; k < scales; ++k) means[k] += s.per_scale[k];
    for (int c = 0; c < 3; ++c) channels[c] += s.channels[c];
  }
  for (double& m : means) m /= n;
  DirectionResult d;
  d.features.fill(0.0);
  if (multiscale) {
    double sum = 0;
    for (int k = 0; k < scales; ++k) {
      sum += means[k];
      d.values.emplace_back("scale" + std::to_string(k), means[k]);
    }
    d.score = sum / scales;
  } else {
    d.score = means[0];
    const char* names[3] = {"channel_l", "channel_m", "channel_n"};
    for (int c = 0; c < 3; ++c) d.values.emplace_back(names[c], channels[c] / n);
  }
  if (!per_element) return d;
  for (const KeypointScores& s : scores) {
    double sum = 0;
    for (int k = 0; k < scales; ++k) sum += s.per_scale[k];
    d.per_element.push_back(sum / scales);
  }
  if (multiscale) {
    for (int k = 0; k < scales; ++k) {
      std::vector<double> v;
      for (const KeypointScores& s : scores) v.push_back(s.per_scale[k]);
      d.per_element_values.emplace_back("scale" + std::to_string(k), std::move(v));
    }
  }
  return d;
}

/// The warnings of a run: keypoints alone in their reference graph, an ignored --direction.
void add_warnings(MetricResult& result, const std::vector<KeypointScores>& scores,
                  const std::string& reference, double eps, const RunOptions& run) {
  const auto lone =
      std::count_if(scores.begin(), scores.end(), [](const KeypointScores& k) { return k.lone; });
  if (lone > 0) {
    result.warnings.push_back(
        reference + ": " + std::to_string(lone) + " of " + std::to_string(scores.size()) +
        " keypoints have at most one other point within the graph radius: they score 0 (the "
        "reference's rule), also against the same cloud; the cloud is sparse at eps " +
        std::to_string(static_cast<long long>(eps)));
  }
  if (run.direction && *run.direction != Direction::kRefToDist) {
    result.warnings.push_back(result.metric +
                              " has one direction (graphs around keypoints of the "
                              "reference): --direction ignored");
  }
}

MetricResult run_graphsim(const std::string& metric, bool multiscale, const Input& ref,
                          const Input& dist, const RunOptions& run, const OptionValues& o) {
  const auto start = std::chrono::steady_clock::now();
  check_thread_count(run.threads);
  const GraphsimParams params = params_of(o, multiscale);
  const ColoredCloud& rc = ref.cloud();
  const ColoredCloud& dc = dist.cloud();
  check_cloud(rc, ref.name(), metric);
  check_cloud(dc, dist.name(), metric);
  const double eps = neighbourhood_radius(rc.positions, ref.name());
  ProgressSteps progress(run.progress, 3);
  progress.begin("keypoints");
  std::string rule;
  const std::vector<std::size_t> keys = keypoints_for(rc.positions, o, run.threads, rule);
  progress.begin("trees");
  const GraphsimCloud r(rc.positions, colours_255(rc.colors), run.threads);
  const GraphsimCloud d(dc.positions, colours_255(dc.colors), run.threads);
  if (run.inputs_done) run.inputs_done();
  progress.begin("keypoint graphs");
  const std::vector<KeypointScores> scores = score_all(r, d, keys, eps, params, run.threads, progress);
  progress.finish();
  MetricResult result;
  result.metric = metric;
  result.ref_to_dist = direction_of(scores, multiscale, params.scales, run.per_element);
  combine_directions(result);
  result.values = result.ref_to_dist->values;
  add_warnings(result, scores, ref.name(), eps, run);
  // keypoint_rows: the keypoints (a keypoint file of them gives the same result); --map writes
  // the per-keypoint scores on their positions.
  result.details = {{"keypoints", keys.size()},
                    {"epsilon", eps},
                    {"keypoint_rule", rule},
                    {"keypoint_rows", keys}};
  result.text_note = "[" + std::to_string(keys.size()) + " keypoints, eps " +
                     std::to_string(static_cast<long long>(eps)) + "]";
  result.provenance.version = kVersion;
  result.provenance.options = o;
  result.provenance.seconds = seconds_since(start);
  return result;
}

/// An option with a lower bound (`exclusive`: the bound itself refused).
OptionSpec option(const std::string& name, const std::string& help, nlohmann::json value,
                  double min, bool exclusive = false) {
  OptionSpec o;
  o.name = name;
  o.help = help;
  o.default_value = std::move(value);
  o.min = min;
  o.min_exclusive = exclusive;
  return o;
}

std::vector<OptionSpec> common_options() {
  OptionSpec file = option("keypoint_file",
                           "File of keypoints: 0-based row indices into the reference, one per "
                           "line (a row given twice counts twice); empty = qm3d's seeded "
                           "variation-score draw",
                           "", 0);
  OptionSpec count = option("keypoints",
                            "Keypoints drawn when no keypoint file is given (0 = round(points / "
                            "10000), at least 1, as the authors' keypoint script)",
                            0, 0);
  count.max = kMaxKeypoints;
  return {file, count, option("seed", "Seed of the keypoint draw (no keypoint file)", 1, 0),
          option("threshold", "T of the mg / mug similarity (2ab + T) / (a^2 + b^2 + T)", 0.001, 0,
                 true),
          option("pooling_weights", "Pooling weights of the L, M, N channels",
                 nlohmann::json::array({6, 1, 1}), 0)};
}

MetricSpec base_spec(const std::string& name, bool multiscale) {
  MetricSpec s;
  s.name = name;
  s.higher_is_better = true;
  s.applies_to = AppliesTo::kClouds;
  s.reads = Input::Kind::kCloud;
  s.in_compare = false;  // keypoints are an input (the published ones were random)
  s.default_direction = Direction::kRefToDist;
  s.direction_help = "one direction: graphs around keypoints of the reference, on both clouds";
  s.symmetric_rule = "one direction";
  s.per_element_on_input = true;  // --map: on the keypoints' positions (details.keypoint_rows)
  s.options = common_options();
  s.run = [name, multiscale](const MetricSpec&, const Input& ref, const Input& dist,
                             const RunOptions& run, const OptionValues& o) {
    return run_graphsim(name, multiscale, ref, dist, run, o);
  };
  return s;
}

}  // namespace

MetricSpec graphsim_spec() {
  MetricSpec s = base_spec("graphsim", false);
  s.title = "GraphSIM";
  s.reproduces = "NJUVISION/GraphSIM @ fdd595d (float64)";
  s.summary =
      "GraphSIM (Yang et al., TPAMI 2020): colour-gradient moments of local graphs around "
      "keypoints of the reference, a similarity (1 = identical); coloured clouds";
  s.value_names = {"channel_l", "channel_m", "channel_n"};
  s.quality_value_names = s.value_names;
  return s;
}

MetricSpec msgraphsim_spec() {
  MetricSpec s = base_spec("msgraphsim", true);
  s.title = "MS-GraphSIM";
  s.reproduces = "zhangyujie-1998/MS_GraphSIM @ b225a59 (float64)";
  s.summary =
      "MS-GraphSIM (Zhang et al., ACM MM 2021): GraphSIM on graphs blurred and resampled over "
      "scales, the mean of the scale scores (1 = identical); coloured clouds";
  s.options.push_back(option("blur_ratio",
                             "r_b: the blur graph's radius as a fraction of the graph radius", 0.5,
                             0, true));
  s.options.push_back(option(
      "sample_ratio", "r_s: each scale keeps every other point and shrinks coordinates by 0.5^r_s",
      1.0 / 3.0, 0, true));
  OptionSpec scales = option("scales", "n_s: scales averaged (scale 0 = GraphSIM)", 3, 1);
  scales.max = kMaxScales;
  s.options.push_back(scales);
  for (int k = 0; k < kMaxScales; ++k) s.value_names.push_back("scale" + std::to_string(k));
  s.quality_value_names = s.value_names;
  return s;
}

}  // namespace qm3d::pointcloud
