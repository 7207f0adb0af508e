// Writing MetricResult: the human line and the JSON object the qm3d tool prints, and the CSV
// helpers batch and merge use (the CSV row itself, the batch row: qm3d/study/batch_row.h). One
// writer serves every metric.
//
// JSON (one metric): {metric, version, reference, distorted, options, score, seconds,
//   directions: {dist_to_ref|ref_to_dist: {score, features: {f1..f8 | F1..F8}, box_size,
//   bbox_max_side}}, [features, box_size, bbox_max_side: the single direction's, when one was
//   computed], warnings, warning_details: [{warning, details}] (what a warning line leaves out,
//   warning.h)}. A metric with named values (psnr) has them as each direction's
//   `features` and its result's as the top-level `features`, no box size, and its `details`
//   entries at the top level. NaN and +-inf are written as null; doubles round-trip exactly.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "qm3d/common/result.h"

namespace qm3d {

/// `CMDM = 0.0421026  (dist→ref 0.0303955, ref→dist 0.0538098)`; a single direction is named
/// in parentheses.
std::string text_line(const MetricResult& r);

/// The JSON object of one result.
nlohmann::json to_json(const MetricResult& r);

/// The JSON object of several metrics on one pair (`qm3d compare --json`): {metric: "compare",
/// version, reference, distorted, metrics: {name: to_json(result)}}.
nlohmann::json compare_json(const std::vector<MetricResult>& results);

/// Quotes a CSV field when needed (RFC 4180; line breaks become spaces).
std::string csv_field(const std::string& s);
/// Splits one CSV line into fields (RFC 4180 quoting).
std::vector<std::string> csv_split(const std::string& line);

/// Shortest text that reads back as the same double ("nan" for NaN).
std::string format_double(double v);

/// Six significant digits, %g style, whatever the locale (1e+19, 0.0421026): the human line's
/// numbers and the values quoted in messages.
std::string short_number(double v);

}  // namespace qm3d
