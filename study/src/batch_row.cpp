#include "qm3d/study/batch_row.h"

#include <optional>
#include <sstream>

#include "qm3d/common/result_io.h"

namespace qm3d::study {
namespace {

constexpr const char* kDirectionColumns[] = {"dist_to_ref", "ref_to_dist"};

void append_direction(std::ostringstream& row, const std::optional<DirectionResult>& d,
                      bool has_features) {
  if (!d) {
    row << std::string(2 + kNumFeatures, ',');
    return;
  }
  row << ',' << format_double(d->score) << ',';
  if (!has_features) {  // a metric of named values: no box, no f1..f8
    row << std::string(kNumFeatures, ',');
    return;
  }
  row << format_double(d->box_size);
  for (double f : d->features) row << ',' << format_double(f);
}

void append_values(std::ostringstream& row, const NamedValues* values,
                   const std::vector<std::string>& names) {
  for (const std::string& name : names) {
    row << ',';
    if (values == nullptr) continue;
    if (const auto v = find_value(*values, name)) row << format_double(*v);
  }
}

void append_all_values(std::ostringstream& row, const MetricResult* r,
                       const std::vector<std::string>& names) {
  if (names.empty()) return;
  append_values(row, r ? &r->values : nullptr, names);
  append_values(row, r && r->dist_to_ref ? &r->dist_to_ref->values : nullptr, names);
  append_values(row, r && r->ref_to_dist ? &r->ref_to_dist->values : nullptr, names);
}

}  // namespace

std::string warnings_field(const std::vector<std::string>& warnings) {
  if (warnings.empty()) return {};
  return std::to_string(warnings.size()) + ": " + warnings.front();
}

std::string csv_header(const std::vector<std::string>& value_names) {
  std::ostringstream h;
  h << "reference,distorted,metric,score,status,error,seconds";
  for (const char* d : kDirectionColumns) {
    h << ',' << d << "_score," << d << "_bbox_max_side";
    for (std::size_t k = 1; k <= kNumFeatures; ++k) h << ',' << d << "_f" << k;
  }
  h << ",warnings";
  for (const std::string& name : value_names) h << ',' << name;
  for (const char* d : kDirectionColumns) {
    for (const std::string& name : value_names) h << ',' << d << '_' << name;
  }
  return h.str();
}

std::string csv_row(const MetricResult& r, const std::string& error,
                    const std::vector<std::string>& value_names) {
  std::ostringstream row;
  row << csv_field(r.provenance.reference) << ',' << csv_field(r.provenance.distorted) << ','
      << csv_field(r.metric) << ',' << format_double(r.score) << ','
      << (error.empty() ? "ok" : "error") << ',' << csv_field(error) << ','
      << format_double(r.provenance.seconds);
  const bool has_features = !r.feature_names.empty() || r.values.empty();
  append_direction(row, r.dist_to_ref, has_features);
  append_direction(row, r.ref_to_dist, has_features);
  row << ',' << csv_field(warnings_field(r.warnings));
  append_all_values(row, &r, value_names);
  return row.str();
}

std::string csv_error_row(const std::string& reference, const std::string& distorted,
                          const std::string& metric, const std::string& error,
                          const std::vector<std::string>& value_names) {
  std::ostringstream row;
  row << csv_field(reference) << ',' << csv_field(distorted) << ',' << csv_field(metric)
      << ",,error," << csv_field(error) << ',';
  append_direction(row, std::nullopt, true);
  append_direction(row, std::nullopt, true);
  row << ',';  // no warnings
  append_all_values(row, nullptr, value_names);
  return row.str();
}

}  // namespace qm3d::study
