// The statistics of an evaluation as JSON, as `qm3d eval --json` writes them (and the Python
// binding returns them).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "qm3d/evaluation/evaluation.h"

namespace qm3d::evaluation {

/// The statistics in their output order, with their names: plcc, srocc, krocc, plcc_logistic,
/// rmse_logistic[, outlier_ratio].
std::vector<std::pair<std::string, Statistic>> named_statistics(const EvaluationResult& r);

/// {"value": v, "ci95": [low, high] or null}; NaN as null.
nlohmann::ordered_json statistic_json(const Statistic& s);

/// The fitted logistic mapping: its formula, beta1..beta4, rmse, converged, bounded.
nlohmann::ordered_json logistic_json(const LogisticFit& fit);

}  // namespace qm3d::evaluation
