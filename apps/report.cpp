#include "report.h"

#include <charconv>
#include <cmath>
#include <sstream>

#include "qm3d/common/version.h"

namespace qm3d::app {
namespace {

constexpr const char* kDirectionColumns[] = {"dist_to_ref", "ref_to_dist"};

nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

nlohmann::json features_json(const FeatureVector& f, const char* prefix) {
  nlohmann::json j = nlohmann::json::object();
  for (std::size_t k = 0; k < kNumFeatures; ++k) j[prefix + std::to_string(k + 1)] = number(f[k]);
  return j;
}

nlohmann::json direction_json(const DirectionReport& d, const char* prefix) {
  return {{"score", number(d.score)},
          {"features", features_json(d.features, prefix)},
          {"bbox_max_side", number(d.bbox_max_side)}};
}

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

std::string short_number(double v) {
  std::ostringstream o;
  o.precision(6);
  o << v;
  return o.str();
}

void append_direction(std::ostringstream& row, const std::optional<DirectionReport>& d) {
  if (!d) {
    row << std::string(2 + kNumFeatures, ',');
    return;
  }
  row << ',' << format_double(d->score) << ',' << format_double(d->bbox_max_side);
  for (double f : d->features) row << ',' << format_double(f);
}

// PCQM on clouds, whether read ("pcqm") or sampled from meshes ("pcqm_sampled").
bool is_pcqm(const std::string& metric) { return metric.rfind("pcqm", 0) == 0; }

}  // namespace

std::string format_double(double v) {
  if (std::isnan(v)) return "nan";
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

std::string text_line(const MetricReport& r) {
  std::ostringstream o;
  o << upper(r.metric) << " = " << short_number(r.score);
  if (r.dist_to_ref && r.ref_to_dist) {
    o << "  (dist\u2192ref " << short_number(r.dist_to_ref->score) << ", ref\u2192dist "
      << short_number(r.ref_to_dist->score) << ")";
  } else if (r.dist_to_ref) {
    o << "  (dist\u2192ref)";
  } else if (r.ref_to_dist && !is_pcqm(r.metric)) {
    o << "  (ref\u2192dist)";
  }
  return o.str();
}

nlohmann::json to_json(const MetricReport& r) {
  // CMDM reports f1..f8 (the paper's names); PCQM F1..F8 (its paper's).
  const char* prefix = is_pcqm(r.metric) ? "F" : "f";
  nlohmann::json j = {{"metric", r.metric},          {"version", kVersion},
                      {"reference", r.reference},    {"distorted", r.distorted},
                      {"options", r.options},        {"score", number(r.score)},
                      {"seconds", number(r.seconds)}};
  nlohmann::json directions = nlohmann::json::object();
  if (r.dist_to_ref) directions["dist_to_ref"] = direction_json(*r.dist_to_ref, prefix);
  if (r.ref_to_dist) directions["ref_to_dist"] = direction_json(*r.ref_to_dist, prefix);
  const bool both = r.dist_to_ref && r.ref_to_dist;
  if (!is_pcqm(r.metric) || both) j["directions"] = directions;
  if (is_pcqm(r.metric) && r.ref_to_dist) {
    // PCQM's own result is the reference -> distorted direction.
    j["features"] = features_json(r.ref_to_dist->features, prefix);
    j["bbox_max_side"] = number(r.ref_to_dist->bbox_max_side);
  }
  j["warnings"] = r.warnings;
  return j;
}

std::string csv_header() {
  std::ostringstream h;
  h << "reference,distorted,metric,score,status,error,seconds";
  for (const char* d : kDirectionColumns) {
    h << ',' << d << "_score," << d << "_bbox_max_side";
    for (std::size_t k = 1; k <= kNumFeatures; ++k) h << ',' << d << "_f" << k;
  }
  return h.str();
}

std::string csv_row(const MetricReport& r, const std::string& error) {
  std::ostringstream row;
  row << csv_field(r.reference) << ',' << csv_field(r.distorted) << ',' << csv_field(r.metric) << ','
      << format_double(r.score) << ',' << (error.empty() ? "ok" : "error") << ','
      << csv_field(error) << ',' << format_double(r.seconds);
  append_direction(row, r.dist_to_ref);
  append_direction(row, r.ref_to_dist);
  return row.str();
}

std::string csv_error_row(const std::string& reference, const std::string& distorted,
                          const std::string& metric, const std::string& error) {
  std::ostringstream row;
  row << csv_field(reference) << ',' << csv_field(distorted) << ',' << csv_field(metric)
      << ",,error," << csv_field(error) << ',';
  append_direction(row, std::nullopt);
  append_direction(row, std::nullopt);
  return row.str();
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

}  // namespace qm3d::app
