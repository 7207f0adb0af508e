// What the qm3d tool prints or writes for one scored pair, and the three ways of writing it
// (human line, JSON object, CSV row). One writer serves every metric and the batch mode.
#pragma once

#include <nlohmann/json.hpp>

#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "qm3d/common/features.h"

namespace qm3d::app {

/// One direction of a metric: which object's elements were iterated.
struct DirectionReport {
  double score = 0;
  FeatureVector features{};
  double bbox_max_side = 0;
};

/// The result of one metric on one pair, as the tool reports it.
struct MetricReport {
  std::string metric;  ///< "cmdm", "pcqm"
  std::string reference;
  std::string distorted;
  nlohmann::json options = nlohmann::json::object();  ///< every option, echoed (provenance)
  double score = 0;
  std::optional<DirectionReport> dist_to_ref;  ///< distorted elements matched on the reference
  std::optional<DirectionReport> ref_to_dist;  ///< reference elements matched on the distorted
  std::vector<std::string> warnings;
  double seconds = 0;
};

/// `CMDM = 0.0421026  (dist->ref 0.0303955, ref->dist 0.0538098)`.
std::string text_line(const MetricReport& r);

/// The JSON object of one report (NaN -> null; doubles round-trip exactly).
nlohmann::json to_json(const MetricReport& r);

/// Fixed CSV header shared by every metric and the batch mode.
std::string csv_header();
/// One CSV row (no newline). `error` non-empty marks a failed pair (score fields empty).
std::string csv_row(const MetricReport& r, const std::string& error = {});
/// A CSV row for a pair that failed before producing any result.
std::string csv_error_row(const std::string& reference, const std::string& distorted,
                          const std::string& metric, const std::string& error);

/// Quotes a CSV field when needed (RFC 4180).
std::string csv_field(const std::string& s);
/// Splits one CSV line into fields (RFC 4180 quoting).
std::vector<std::string> csv_split(const std::string& line);

/// Shortest text that reads back as the same double ("nan" for NaN).
std::string format_double(double v);

}  // namespace qm3d::app
