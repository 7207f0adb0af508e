// The batch row: the one CSV row of a result, written by `qm3d batch` (with a last settings
// column, batch_results.h), `qm3d merge`, `qm3d score --csv` and, through the bindings,
// Python's MetricResult.csv_row and qm3d.dask. Columns: csv_header(); bbox_max_side columns hold
// box_size. Fields are quoted and numbers written by result_io.h's csv_field / format_double.
#pragma once

#include <string>
#include <vector>

#include "qm3d/common/result.h"

namespace qm3d::study {

/// The CSV header shared by every metric and the batch mode: fixed columns (the f1..f8 of each
/// direction, then `warnings`: warnings_field()), then, for each name of `value_names` (the named
/// values of the metrics written: MetricSpec::value_names, see metric.h csv_value_names), a column
/// `NAME` (the result's values) and columns `dist_to_ref_NAME`, `ref_to_dist_NAME`. No value names:
/// the fixed columns only.
std::string csv_header(const std::vector<std::string>& value_names = {});
/// The `warnings` field of a row: empty, or "N: FIRST" (their count and the first message).
std::string warnings_field(const std::vector<std::string>& warnings);
/// One CSV row (no newline) under csv_header(value_names). `error` non-empty marks a failed
/// pair. A value the result lacks is an empty field; an infinite one "inf".
std::string csv_row(const MetricResult& r, const std::string& error = {},
                    const std::vector<std::string>& value_names = {});
/// A CSV row for a pair that failed before producing any result.
std::string csv_error_row(const std::string& reference, const std::string& distorted,
                          const std::string& metric, const std::string& error,
                          const std::vector<std::string>& value_names = {});

}  // namespace qm3d::study
