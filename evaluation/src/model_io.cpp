#include "qm3d/evaluation/model_io.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>

#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"

namespace qm3d::evaluation {
namespace {

using nlohmann::json;

constexpr std::array<const char*, 6> kKnownKeys = {"format",  "metric",     "features",
                                                   "weights", "provenance", "logistic"};
constexpr std::array<const char*, 4> kLogisticKeys = {"beta1", "beta2", "beta3", "beta4"};
/// Largest model file read (a model is a few hundred bytes; this only guards against reading
/// a wrong, huge file).
constexpr std::uintmax_t kMaxModelBytes = std::uintmax_t(1) << 20;

[[noreturn]] void fail(const std::string& source, const std::string& what) {
  throw FormatError(source + ": model file: " + what);
}

const json& member(const json& j, const char* key, json::value_t type, const char* type_name,
                   const std::string& source) {
  if (!j.contains(key)) fail(source, std::string("missing \"") + key + "\"");
  const json& v = j.at(key);
  const bool ok = type == json::value_t::number_float ? v.is_number() : v.type() == type;
  if (!ok) fail(source, std::string("\"") + key + "\" must be " + type_name);
  return v;
}

void check_keys(const json& j, const std::string& source) {
  for (const auto& item : j.items()) {
    const bool known = std::any_of(kKnownKeys.begin(), kKnownKeys.end(),
                                   [&](const char* k) { return item.key() == k; });
    if (!known) fail(source, "unknown key \"" + item.key() + "\"");
  }
  if (j.contains("format") && j.at("format") != kModelFormat) {
    fail(source, std::string("\"format\" must be \"") + kModelFormat + "\"");
  }
}

double finite_number(const json& v, const std::string& what, const std::string& source) {
  if (!v.is_number()) fail(source, what + " must be a number");
  const double d = v.get<double>();
  if (!std::isfinite(d)) fail(source, what + " is not finite");
  return d;
}

FeatureVector parse_weights(const json& j, const std::string& source) {
  const json& names = member(j, "features", json::value_t::array, "an array of names", source);
  const json& values = member(j, "weights", json::value_t::array, "an array of numbers", source);
  if (names.size() != values.size()) {
    fail(source, "\"features\" has " + std::to_string(names.size()) + " names but \"weights\" " +
                     std::to_string(values.size()) + " numbers");
  }
  if (names.empty()) fail(source, "no feature listed");
  FeatureVector weights{};
  std::set<std::size_t> seen;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (!names[i].is_string()) fail(source, "\"features\" must hold names like \"f3\"");
    std::size_t k = 0;
    try {
      k = feature_index(names[i].get<std::string>());
    } catch (const FormatError& e) {
      fail(source, e.what());
    }
    if (!seen.insert(k).second) fail(source, "feature " + feature_name(k) + " listed twice");
    weights[k] = finite_number(values[i], "weight of " + feature_name(k), source);
  }
  return weights;
}

LogisticFunction parse_logistic(const json& j, const std::string& source) {
  if (!j.is_object()) fail(source, "\"logistic\" must be an object");
  std::array<double, 4> beta{};
  for (std::size_t k = 0; k < kLogisticKeys.size(); ++k) {
    if (!j.contains(kLogisticKeys[k])) {
      fail(source, std::string("\"logistic\" lacks \"") + kLogisticKeys[k] + "\"");
    }
    beta[k] =
        finite_number(j.at(kLogisticKeys[k]), std::string("logistic ") + kLogisticKeys[k], source);
  }
  return {beta[0], beta[1], beta[2], beta[3]};
}

nlohmann::ordered_json logistic_json(const LogisticFunction& f) {
  return {{"beta1", f.beta1}, {"beta2", f.beta2}, {"beta3", f.beta3}, {"beta4", f.beta4}};
}

}  // namespace

std::size_t feature_index(const std::string& name) {
  const bool ok = name.size() == 2 && (name[0] == 'f' || name[0] == 'F') && name[1] >= '1' &&
                  name[1] <= static_cast<char>('0' + kNumFeatures);
  if (!ok) throw FormatError("unknown feature \"" + name + "\" (expected f1..f8)");
  return static_cast<std::size_t>(name[1] - '1');
}

std::string feature_name(std::size_t index) { return "f" + std::to_string(index + 1); }

ModelFile parse_model(const std::string& json_text, const std::string& source) {
  const json j = json::parse(json_text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) fail(source, "not valid JSON");
  if (!j.is_object()) fail(source, "the top level must be a JSON object");
  check_keys(j, source);
  ModelFile m;
  m.model.metric =
      member(j, "metric", json::value_t::string, "a string", source).get<std::string>();
  if (m.model.metric.empty()) fail(source, "\"metric\" is empty");
  m.model.weights = parse_weights(j, source);
  if (std::all_of(m.model.weights.begin(), m.model.weights.end(),
                  [](double w) { return w == 0; })) {
    fail(source, "every weight is 0");
  }
  if (j.contains("provenance")) {
    m.model.provenance =
        member(j, "provenance", json::value_t::string, "a string", source).get<std::string>();
  }
  if (j.contains("logistic")) m.mos_mapping = parse_logistic(j.at("logistic"), source);
  return m;
}

ModelFile read_model(const std::filesystem::path& path) {
  return parse_model(read_file_bytes(path, kMaxModelBytes), path.string());
}

LinearModel read_model_for(const std::filesystem::path& path, const std::string& metric) {
  LinearModel m = read_model(path).model;
  if (m.metric != metric) {
    fail(path.string(), "it is a \"" + m.metric + "\" model, not a \"" + metric + "\" one");
  }
  m.provenance +=
      (m.provenance.empty() ? "" : " ") + std::string("(model file ") + path.string() + ")";
  return m;
}

std::string model_to_json(const ModelFile& model) {
  using ordered = nlohmann::ordered_json;
  ordered names = ordered::array(), weights = ordered::array();
  for (std::size_t k = 0; k < kNumFeatures; ++k) {
    if (model.model.weights[k] == 0.0) continue;
    names.push_back(feature_name(k));
    weights.push_back(model.model.weights[k]);
  }
  ordered j = {{"format", kModelFormat},
               {"metric", model.model.metric},
               {"features", names},
               {"weights", weights},
               {"provenance", model.model.provenance}};
  if (model.mos_mapping) j["logistic"] = logistic_json(*model.mos_mapping);
  return j.dump(2) + "\n";
}

void write_model(const std::filesystem::path& path, const ModelFile& model) {
  const std::string text = model_to_json(model);
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace qm3d::evaluation
