// PointSSIM (qm3d/pointcloud/pointssim.h): its two directions, pooling and symmetric rule, and
// its registry entry. The reference is mmspg/pointssim @ 2358dd3 (MATLAB; its numbers were made
// under Octave 7.3, ../shared/data/reference/pointssim/README.md); qm3d implements it from the
// paper and the rules of ../shared/docs/SPEC-POINTSSIM.md.
#include "qm3d/pointcloud/pointssim.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <type_traits>

#include "pointssim_internal.h"
#include "qm3d/common/error.h"
#include "qm3d/common/metric.h"
#include "qm3d/common/version.h"
#include "qm3d/pointcloud/metrics.h"

namespace qm3d::pointcloud {
namespace {

using detail::FeatureMaps;
using detail::OrderedSearch;
using detail::SsimCloud;
using detail::SurfaceEstimates;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
/// The error map's constant: MATLAB's eps(1) (PARAMS.CONST of the reference).
constexpr double kErrorConstant = std::numeric_limits<double>::epsilon();
/// main.m's default fit radius: this share of the reference's largest extent, rounded.
constexpr double kDefaultRadiusRatio = 0.01;
/// A quadric has six coefficients: a fit needs at least that many points.
constexpr std::size_t kQuadricTerms = 6;
constexpr int kMinNeighbours = 3;

constexpr std::array<PointssimAttribute, 4> kAttributes{
    PointssimAttribute::kGeom, PointssimAttribute::kNorm, PointssimAttribute::kCurv,
    PointssimAttribute::kColor};
constexpr std::array<PointssimEstimator, 7> kEstimators{
    PointssimEstimator::kStd,      PointssimEstimator::kVar, PointssimEstimator::kMeanAd,
    PointssimEstimator::kMedianAd, PointssimEstimator::kCov, PointssimEstimator::kQcd,
    PointssimEstimator::kMean};
constexpr std::array<PointssimPooling, 3> kPoolings{PointssimPooling::kMean, PointssimPooling::kMse,
                                                    PointssimPooling::kRmse};

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// A list of names (comma-separated, case-insensitive, or "all") as enum values in the canonical
// order, each once.
template <typename T, std::size_t N>
std::vector<T> parse_list(const std::string& list, const std::string& option,
                          const std::array<T, N>& all) {
  std::string known;
  for (T v : all) known += std::string(known.empty() ? "" : ", ") + pointssim_name(v);
  std::vector<bool> chosen(N, false);
  std::size_t start = 0;
  const std::string text = lower(list);
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    std::string item = text.substr(start, end - start);
    item.erase(0, item.find_first_not_of(" \t"));
    item.erase(item.find_last_not_of(" \t") + 1);
    if (item == "all") {
      chosen.assign(N, true);
    } else if (item == "colour" && std::is_same_v<T, PointssimAttribute>) {
      chosen[static_cast<std::size_t>(PointssimAttribute::kColor)] = true;
    } else {
      std::size_t k = 0;
      while (k < N && item != pointssim_name(all[k])) ++k;
      if (k == N) {
        throw std::invalid_argument(option + ": unknown name '" + item + "' in '" + list +
                                    "' (known: " + known + ", or all)");
      }
      chosen[k] = true;
    }
    start = end + 1;
  }
  std::vector<T> out;
  for (std::size_t k = 0; k < N; ++k) {
    if (chosen[k]) out.push_back(all[k]);
  }
  return out;
}

void check_size(const SsimCloud& c, std::size_t needed, const std::string& name,
                const std::string& why) {
  if (c.points.size() >= needed) return;
  throw NumericError(name + ": " + std::to_string(c.points.size()) +
                     " distinct points; pointssim needs at least " + std::to_string(needed) + " (" +
                     why + ")");
}

// main.m's radius: round(0.01 x the largest side of the reference's (fused) bounding box).
double default_radius(const SsimCloud& reference) {
  Vec3 lo = reference.points.front(), hi = lo;
  for (const Vec3& p : reference.points) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
  }
  const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  const double radius = std::round(kDefaultRadiusRatio * extent);
  if (radius <= 0) {
    throw std::invalid_argument(
        "fit_radius: the reference's default fit radius round(0.01 x largest extent " +
        std::to_string(extent) +
        ") is 0 (the reference code stops here too); give --fit-radius R "
        "or --fit-knn N");
  }
  return radius;
}

/// One cloud ready to be scored.
struct Scored {
  SsimCloud cloud;
  std::unique_ptr<OrderedSearch> search;
  SurfaceEstimates surface;  ///< when normals or curvature are compared
  FeatureMaps features;
};

// The similarity map of Y's rows against X's features at their nearest rows `nearest`:
// 1 - |fX - fY| / (max(|fX|, |fY|) + eps(1)).
std::vector<double> similarity_map(const std::vector<double>& fx, const std::vector<double>& fy,
                                   const std::vector<std::uint32_t>& nearest) {
  std::vector<double> s(fy.size());
  for (std::size_t i = 0; i < fy.size(); ++i) {
    const double x = fx[nearest[i]], y = fy[i];
    s[i] = 1 - std::abs(x - y) / (std::max(std::abs(x), std::abs(y)) + kErrorConstant);
  }
  return s;
}

// nanmean of s (or of s^2): the non-NaN values summed in row order over their count.
double pool(const std::vector<double>& s, PointssimPooling p) {
  double sum = 0;
  std::size_t count = 0;
  for (double v : s) {
    if (std::isnan(v)) continue;
    sum += p == PointssimPooling::kMean ? v : v * v;
    ++count;
  }
  const double m = count == 0 ? kNan : sum / static_cast<double>(count);
  return p == PointssimPooling::kRmse ? std::sqrt(m) : m;
}

// Each row of `from`'s nearest row in `to` (the reference's knnsearch with K = 1).
std::vector<std::uint32_t> nearest_rows(const Scored& from, const Scored& to, int threads) {
  const std::vector<Vec3>& points = from.cloud.points;
  std::vector<std::uint32_t> out(points.size());
  const long n = static_cast<long>(points.size());
#pragma omp parallel num_threads(threads > 0 ? threads : omp_get_max_threads())
  {
    std::vector<detail::Neighbour> nb;
#pragma omp for schedule(dynamic, 1024)
    for (long i = 0; i < n; ++i) {
      to.search->knn(points[static_cast<std::size_t>(i)], 1, nb);
      out[static_cast<std::size_t>(i)] = nb.front().index;
    }
  }
  return out;
}

/// The resolved choice of values.
struct Request {
  std::vector<PointssimAttribute> attributes;
  std::vector<PointssimEstimator> estimators;
  std::vector<PointssimPooling> poolings;
  std::size_t score_map = 0;      ///< attribute x estimator slot of the score
  std::size_t score_pooling = 0;  ///< index in poolings
  std::string score_name;
  bool colours = false;  ///< colour is compared
};

template <typename T>
std::size_t index_or_first(const std::vector<T>& list, T wanted) {
  const auto it = std::find(list.begin(), list.end(), wanted);
  return it == list.end() ? 0 : static_cast<std::size_t>(it - list.begin());
}

// The score: color_var_mean when colour is compared, else geom_var_mean; a list without that
// attribute / estimator / pooling gives its first one instead.
Request make_request(std::vector<PointssimAttribute> attributes, const PointssimOptions& o) {
  Request r;
  r.attributes = std::move(attributes);
  r.estimators = o.estimators;
  r.poolings = o.poolings;
  if (r.estimators.empty() || r.poolings.empty()) {
    throw std::invalid_argument("pointssim: at least one estimator and one pooling are needed");
  }
  r.colours = std::count(r.attributes.begin(), r.attributes.end(), PointssimAttribute::kColor) > 0;
  const std::size_t a = index_or_first(
      r.attributes, r.colours ? PointssimAttribute::kColor : PointssimAttribute::kGeom);
  const std::size_t e = index_or_first(r.estimators, PointssimEstimator::kVar);
  r.score_map = a * r.estimators.size() + e;
  r.score_pooling = index_or_first(r.poolings, PointssimPooling::kMean);
  r.score_name =
      pointssim_value_name(r.attributes[a], r.estimators[e], r.poolings[r.score_pooling]);
  return r;
}

bool has_colours(const ColoredCloud& c) {
  return !c.colors.empty() && c.colors.size() == c.positions.size();
}

std::vector<PointssimAttribute> resolve_attributes(const PointssimOptions& o, const ColoredCloud& a,
                                                   const ColoredCloud& b, const std::string& a_name,
                                                   const std::string& b_name) {
  if (o.attributes.empty()) {
    std::vector<PointssimAttribute> all{PointssimAttribute::kGeom, PointssimAttribute::kNorm,
                                        PointssimAttribute::kCurv};
    if (has_colours(a) && has_colours(b)) all.push_back(PointssimAttribute::kColor);
    return all;
  }
  if (std::count(o.attributes.begin(), o.attributes.end(), PointssimAttribute::kColor)) {
    for (const auto& [cloud, name] : {std::pair{&a, &a_name}, std::pair{&b, &b_name}}) {
      if (!has_colours(*cloud)) {
        throw FormatError(*name +
                          ": no colours (pointssim's colour attribute needs one colour "
                          "per point: red/green/blue vertex properties)");
      }
    }
  }
  return o.attributes;
}

bool needs_surface(const Request& r) {
  return std::any_of(r.attributes.begin(), r.attributes.end(), [](PointssimAttribute a) {
    return a == PointssimAttribute::kNorm || a == PointssimAttribute::kCurv;
  });
}

// The direction that scores `iterated`'s rows against `other`.
DirectionResult score_direction(const Scored& iterated, const Scored& other, const Request& r,
                                int threads, bool per_element) {
  const std::vector<std::uint32_t> nearest = nearest_rows(iterated, other, threads);
  DirectionResult d;
  d.features.fill(0.0);
  for (std::size_t a = 0; a < r.attributes.size(); ++a) {
    for (std::size_t e = 0; e < r.estimators.size(); ++e) {
      const std::size_t slot = a * r.estimators.size() + e;
      const std::vector<double> s =
          similarity_map(other.features.maps[slot], iterated.features.maps[slot], nearest);
      for (PointssimPooling p : r.poolings) {
        d.values.emplace_back(pointssim_value_name(r.attributes[a], r.estimators[e], p),
                              pool(s, p));
      }
      if (slot != r.score_map) continue;
      d.score = pool(s, r.poolings[r.score_pooling]);
      if (!per_element) continue;
      d.per_element.resize(iterated.cloud.of_input.size());
      for (std::size_t i = 0; i < d.per_element.size(); ++i) {
        d.per_element[i] = s[iterated.cloud.of_input[i]];
      }
    }
  }
  return d;
}

// MATLAB's min(x, y): the lower one, a NaN operand ignored.
double min_ignoring_nan(double x, double y) {
  if (std::isnan(x)) return y;
  if (std::isnan(y)) return x;
  return std::min(x, y);
}

NamedValues symmetric_values(const DirectionResult& ab, const DirectionResult& ba) {
  NamedValues out;
  for (std::size_t k = 0; k < ab.values.size(); ++k) {
    out.emplace_back(ab.values[k].first,
                     min_ignoring_nan(ab.values[k].second, ba.values[k].second));
  }
  return out;
}

// Leaves out the NaN values (no finite similarity at all), with one warning per name.
void drop_nan(NamedValues& values, const std::string& where, std::vector<std::string>& warnings) {
  for (auto it = values.begin(); it != values.end();) {
    if (!std::isnan(it->second)) {
      ++it;
      continue;
    }
    warnings.push_back("pointssim: " + where + it->first +
                       " is not a number (no point has a finite similarity: e.g. COV of "
                       "features whose mean is 0); left out");
    it = values.erase(it);
  }
}

std::unique_ptr<Scored> prepare(const ColoredCloud& cloud, bool colours, const std::string& name,
                                int threads) {
  if (cloud.positions.empty()) throw NumericError(name + ": the cloud is empty");
  auto s = std::make_unique<Scored>();
  s->cloud = detail::prepare_cloud(cloud, colours, name);
  s->search = std::make_unique<OrderedSearch>(s->cloud.points, threads);
  return s;
}

detail::FitNeighbourhood fit_neighbourhood(const PointssimOptions& o, const Scored& reference) {
  detail::FitNeighbourhood fit;
  if (o.fit == PointssimFit::kKnn) {
    if (!(o.fit_size >= 1)) throw std::invalid_argument("fit_knn: at least 1 neighbour");
    fit.count = static_cast<std::size_t>(o.fit_size);
  } else if (o.fit == PointssimFit::kRadius) {
    if (!(o.fit_size > 0)) throw std::invalid_argument("fit_radius: must be > 0");
    fit.radius = o.fit_size;
  } else {
    fit.radius = default_radius(reference.cloud);
  }
  return fit;
}

nlohmann::json list_json(const Request& r) {
  nlohmann::json a = nlohmann::json::array(), e = nlohmann::json::array(),
                 p = nlohmann::json::array();
  for (auto v : r.attributes) a.push_back(pointssim_name(v));
  for (auto v : r.estimators) e.push_back(pointssim_name(v));
  for (auto v : r.poolings) p.push_back(pointssim_name(v));
  return {{"attributes", a}, {"estimators", e}, {"poolings", p}};
}

// Both directions the options ask for, their values and the symmetric ones, NaN values left out.
MetricResult score_directions(const Scored& a, const Scored& b, const Request& r,
                              const PointssimOptions& o) {
  const Direction dir = o.direction.value_or(Direction::kSymmetric);
  MetricResult result;
  result.metric = "pointssim";
  if (dir != Direction::kDistToRef) {
    result.ref_to_dist = score_direction(a, b, r, o.threads, o.per_element);  // AB
  }
  if (dir != Direction::kRefToDist) {
    result.dist_to_ref = score_direction(b, a, r, o.threads, o.per_element);  // BA
  }
  if (result.ref_to_dist && result.dist_to_ref) {
    result.values = symmetric_values(*result.ref_to_dist, *result.dist_to_ref);
  } else {
    result.values = result.any_direction().values;
  }
  result.score = *find_value(result.values, r.score_name);
  drop_nan(result.values, "", result.warnings);
  if (result.ref_to_dist) drop_nan(result.ref_to_dist->values, "ref-to-dist ", result.warnings);
  if (result.dist_to_ref) drop_nan(result.dist_to_ref->values, "dist-to-ref ", result.warnings);
  return result;
}

// The result's warnings (fused duplicates), details and provenance.
void describe(MetricResult& result, const Scored& a, const Scored& b, const Request& r,
              const PointssimOptions& o, const std::optional<detail::FitNeighbourhood>& fit,
              const std::array<std::string, 2>& names) {
  const std::array<const Scored*, 2> clouds{&a, &b};
  for (std::size_t c = 0; c < 2; ++c) {
    if (clouds[c]->cloud.duplicates == 0) continue;
    result.warnings.push_back(names[c] + ": " + std::to_string(clouds[c]->cloud.duplicates) +
                              " duplicate points fused (pointssim scores distinct positions" +
                              (r.colours ? ", colours averaged)" : ")"));
  }
  nlohmann::json fit_json = nullptr;
  if (fit) {
    fit_json = fit->count > 0 ? nlohmann::json{{"method", "knn"}, {"size", fit->count}}
                              : nlohmann::json{{"method", "radius"}, {"size", fit->radius}};
  }
  result.details = {
      {"score_value", r.score_name},
      {"points", {{"reference", a.cloud.points.size()}, {"distorted", b.cloud.points.size()}}},
      {"duplicates_fused", {{"reference", a.cloud.duplicates}, {"distorted", b.cloud.duplicates}}},
      {"fit", fit_json}};
  result.text_note = "[" + r.score_name + "; 1 = identical]";
  result.provenance.version = kVersion;
  result.provenance.options = list_json(r);
  result.provenance.options["direction"] =
      direction_name(o.direction.value_or(Direction::kSymmetric));
  result.provenance.options["neighbours"] = o.neighbours;
  result.provenance.options["fit"] = fit_json;
}

}  // namespace

const char* pointssim_name(PointssimAttribute a) {
  static const char* const names[] = {"geom", "norm", "curv", "color"};
  return names[static_cast<int>(a)];
}
const char* pointssim_name(PointssimEstimator e) {
  static const char* const names[] = {"std", "var", "meanad", "medianad", "cov", "qcd", "mean"};
  return names[static_cast<int>(e)];
}
const char* pointssim_name(PointssimPooling p) {
  static const char* const names[] = {"mean", "mse", "rmse"};
  return names[static_cast<int>(p)];
}

std::string pointssim_value_name(PointssimAttribute a, PointssimEstimator e, PointssimPooling p) {
  return std::string(pointssim_name(a)) + "_" + pointssim_name(e) + "_" + pointssim_name(p);
}

std::vector<std::string> pointssim_value_names() {
  std::vector<std::string> out;
  for (auto a : kAttributes) {
    for (auto e : kEstimators) {
      for (auto p : kPoolings) out.push_back(pointssim_value_name(a, e, p));
    }
  }
  return out;
}

std::vector<PointssimAttribute> parse_pointssim_attributes(const std::string& list,
                                                           const std::string& option) {
  return parse_list(list, option, kAttributes);
}
std::vector<PointssimEstimator> parse_pointssim_estimators(const std::string& list,
                                                           const std::string& option) {
  return parse_list(list, option, kEstimators);
}
std::vector<PointssimPooling> parse_pointssim_poolings(const std::string& list,
                                                       const std::string& option) {
  return parse_list(list, option, kPoolings);
}

MetricResult compute_pointssim(const ColoredCloud& reference, const ColoredCloud& distorted,
                               const PointssimOptions& o, const std::string& reference_name,
                               const std::string& distorted_name) {
  const auto start = std::chrono::steady_clock::now();
  check_thread_count(o.threads);
  if (o.neighbours < kMinNeighbours) throw std::invalid_argument("neighbours: at least 3");
  const Request r =
      make_request(resolve_attributes(o, reference, distorted, reference_name, distorted_name), o);
  ProgressSteps progress(o.progress, 4);
  progress.begin("sorting and fusing points");
  const auto a = prepare(reference, r.colours, reference_name, o.threads);
  const auto b = prepare(distorted, r.colours, distorted_name, o.threads);
  if (o.inputs_done) o.inputs_done();
  const auto k = static_cast<std::size_t>(o.neighbours);
  const std::string why_k = "the neighbourhood of " + std::to_string(k) + " points";
  check_size(a->cloud, k, reference_name, why_k);
  check_size(b->cloud, k, distorted_name, why_k);
  progress.begin("normals and curvatures");
  std::optional<detail::FitNeighbourhood> fit;
  if (needs_surface(r)) {
    fit = fit_neighbourhood(o, *a);
    const std::size_t needed = std::max(kQuadricTerms, fit->count);
    const std::string why_fit = "a quadric fit of " + std::to_string(needed) + " points";
    check_size(a->cloud, needed, reference_name, why_fit);
    check_size(b->cloud, needed, distorted_name, why_fit);
    for (Scored* s : {a.get(), b.get()}) {
      s->surface = detail::estimate_surface(s->cloud.points, *s->search, *fit, k, o.threads);
    }
  }
  progress.begin("features");
  for (Scored* s : {a.get(), b.get()}) {
    s->features = detail::feature_maps(s->cloud, *s->search, fit ? &s->surface : nullptr, k,
                                       r.attributes, r.estimators, o.threads);
  }
  progress.begin("similarity maps");
  MetricResult result = score_directions(*a, *b, r, o);
  describe(result, *a, *b, r, o, fit, {reference_name, distorted_name});
  result.provenance.seconds = seconds_since(start);
  progress.finish();
  return result;
}

MetricSpec pointssim_spec() {
  MetricSpec s;
  s.name = "pointssim";
  s.title = "PointSSIM";
  s.reproduces = "mmspg/pointssim @ 2358dd3";
  s.summary =
      "PointSSIM (Alexiou & Ebrahimi, ICMEW 2020): structural similarity of two point clouds "
      "(meshes by their vertices) from local statistics of geometry, normals, curvature and "
      "colour; score = color_var_mean for coloured clouds, else geom_var_mean (1 = identical)";
  s.higher_is_better = true;
  s.applies_to = AppliesTo::kBoth;
  s.reads = Input::Kind::kCloud;
  // Asked for by name only: its default fit radius (the reference's main.m rule) is 0 on
  // unit-size float clouds, where it stops with an error.
  s.in_compare = false;
  s.default_direction = Direction::kSymmetric;
  s.direction_help =
      "symmetric: both directions, each value the lower similarity of the two (the reference's "
      "Sym; a NaN one ignored); ref-to-dist: the reference's points scored against the distorted "
      "cloud (the reference's AB); dist-to-ref: the distorted cloud's points (BA)";
  s.symmetric_rule = "lower of the two";
  s.per_element_on_input = true;
  s.value_names = pointssim_value_names();
  s.quality_value_names = s.value_names;
  s.options = {
      {"neighbours",
       "K, the neighbourhood of each point's statistics, the point itself included "
       "(the reference's NEIGHBORHOOD_SIZE)",
       12,
       {},
       kMinNeighbours,
       100000},
      {"fit_knn",
       "Normals and curvatures fitted on the N nearest points (self included); 0 = not this way",
       0,
       {},
       0,
       100000},
      {"fit_radius",
       "Normals and curvatures fitted on the points within R (inclusive); 0 with fit_knn 0 = the "
       "reference's main.m rule, R = round(0.01 x the reference's largest extent)",
       0.0,
       {},
       0,
       1e300},
      {"estimators",
       "Comma-separated estimators: std, var, meanad, medianad, cov, qcd, mean, or all",
       "var",
       {}},
      {"poolings",
       "Comma-separated poolings of the similarity maps: mean, mse, rmse, or all",
       "mean",
       {}},
      {"attributes",
       "Comma-separated attributes: geom, norm, curv, color, or all; auto = geom, norm, curv and "
       "color when both clouds have colours",
       "auto",
       {}},
  };
  s.run = [](const MetricSpec&, const Input& ref, const Input& dist, const RunOptions& run,
             const OptionValues& v) {
    PointssimOptions o;
    static_cast<RunOptions&>(o) = run;
    o.neighbours = v.at("neighbours").get<int>();
    const int knn = v.at("fit_knn").get<int>();
    const double radius = v.at("fit_radius").get<double>();
    if (knn > 0 && radius > 0) {
      throw std::invalid_argument("fit_knn and fit_radius: give one of them, not both");
    }
    o.fit = knn > 0      ? PointssimFit::kKnn
            : radius > 0 ? PointssimFit::kRadius
                         : PointssimFit::kDefaultRadius;
    o.fit_size = knn > 0 ? knn : radius;
    o.estimators = parse_pointssim_estimators(v.at("estimators").get<std::string>(), "estimators");
    o.poolings = parse_pointssim_poolings(v.at("poolings").get<std::string>(), "poolings");
    const std::string attributes = lower(v.at("attributes").get<std::string>());
    if (attributes != "auto") o.attributes = parse_pointssim_attributes(attributes, "attributes");
    return compute_pointssim(ref.cloud(), dist.cloud(), o, ref.name(), dist.name());
  };
  return s;
}

}  // namespace qm3d::pointcloud
