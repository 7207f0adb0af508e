#include "qm3d/common/result_io.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <optional>
#include <sstream>

#include "qm3d/common/version.h"

namespace qm3d {
namespace {

nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

nlohmann::json features_json(const MetricResult& r, const FeatureVector& f) {
  nlohmann::json j = nlohmann::json::object();
  for (std::size_t k = 0; k < kNumFeatures; ++k) {
    j[k < r.feature_names.size() ? r.feature_names[k] : "f" + std::to_string(k + 1)] = number(f[k]);
  }
  return j;
}

nlohmann::json values_json(const NamedValues& values) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [name, v] : values) j[name] = number(v);
  return j;
}

// `bbox_max_side` is the name of `box_size` before it was named for what it is; kept so that
// existing readers of the JSON keep working. A metric of named values has no f1..f8 and no box.
void add_direction(nlohmann::json& j, const MetricResult& r, const DirectionResult& d) {
  if (!d.values.empty() || (r.feature_names.empty() && !r.values.empty())) {
    j["features"] = values_json(d.values);
    return;
  }
  j["features"] = features_json(r, d.features);
  j["box_size"] = number(d.box_size);
  j["bbox_max_side"] = number(d.box_size);
}

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

std::string short_number(double v) {
  std::ostringstream o;
  o.imbue(std::locale::classic());
  o.precision(6);
  o << v;
  return o.str();
}

std::string format_double(double v) {
  if (std::isnan(v)) return "nan";
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

std::string text_line(const MetricResult& r) {
  std::ostringstream o;
  o << upper(r.metric) << " = " << short_number(r.score);
  if (r.dist_to_ref && r.ref_to_dist) {
    o << "  (dist\u2192ref " << short_number(r.dist_to_ref->score) << ", ref\u2192dist "
      << short_number(r.ref_to_dist->score) << ")";
  } else if (r.dist_to_ref) {
    o << "  (dist\u2192ref)";
  } else if (r.ref_to_dist) {
    o << "  (ref\u2192dist)";
  }
  if (!r.text_note.empty()) o << "  " << r.text_note;
  return o.str();
}

nlohmann::json to_json(const MetricResult& r) {
  const Provenance& p = r.provenance;
  nlohmann::json j = {{"metric", r.metric},
                      {"version", p.version.empty() ? std::string(kVersion) : p.version},
                      {"commit", git_commit()},
                      {"reference", p.reference},
                      {"distorted", p.distorted},
                      {"options", p.options},
                      {"score", number(r.score)},
                      {"seconds", number(p.seconds)}};
  nlohmann::json directions = nlohmann::json::object();
  if (r.dist_to_ref) {
    directions["dist_to_ref"] = {{"score", number(r.dist_to_ref->score)}};
    add_direction(directions["dist_to_ref"], r, *r.dist_to_ref);
  }
  if (r.ref_to_dist) {
    directions["ref_to_dist"] = {{"score", number(r.ref_to_dist->score)}};
    add_direction(directions["ref_to_dist"], r, *r.ref_to_dist);
  }
  if (!p.reproduces.empty()) j["reproduces"] = p.reproduces;
  j["directions"] = directions;
  // One direction: its features at the top level too (PCQM's own output is its one direction).
  if (!r.values.empty()) {
    j["features"] = values_json(r.values);
  } else if (static_cast<bool>(r.dist_to_ref) != static_cast<bool>(r.ref_to_dist)) {
    add_direction(j, r, r.any_direction());
  }
  for (const auto& [key, value] : r.details.items()) j[key] = value;
  j["warnings"] = r.warnings;
  // What each warning line leaves out (warning.h): [{warning, details}], empty when none.
  j["warning_details"] = nlohmann::json::array();
  for (const WarningDetails& d : r.warning_details) {
    j["warning_details"].push_back({{"warning", d.warning}, {"details", d.details}});
  }
  return j;
}

nlohmann::json compare_json(const std::vector<MetricResult>& results) {
  nlohmann::json j = {{"metric", "compare"}, {"version", kVersion}};
  if (!results.empty()) {
    j["reference"] = results.front().provenance.reference;
    j["distorted"] = results.front().provenance.distorted;
  }
  j["metrics"] = nlohmann::json::object();
  for (const auto& r : results) j["metrics"][r.metric] = to_json(r);
  return j;
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) {
    if (c == '"') q += '"';
    q += (c == '\n' || c == '\r') ? ' ' : c;
  }
  return q + "\"";
}

std::vector<std::string> csv_split(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        fields.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        fields.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else if (c != '\r') {
      fields.back() += c;
    }
  }
  return fields;
}

}  // namespace qm3d
