#include "qm3d/evaluation/orientation.h"

#include <algorithm>

namespace qm3d::evaluation {

Orientation orient(const Registry& registry, const OrientationRequest& request,
                   const SeriesName& series, Fallback fallback) {
  const auto& lower = request.lower_is_better;
  if (std::find(lower.begin(), lower.end(), series.name) != lower.end()) {
    return {false, request.lower_is_better_option};
  }
  if (request.orientation != "auto") {
    return {request.orientation == "quality", request.orientation_option};
  }
  if (const MetricSpec* spec = series.metric.empty() ? nullptr : registry.find(series.metric)) {
    if (const auto h = spec->column_higher_is_better(series.column)) {
      return {*h, "metric column: " + series.metric};
    }
  }
  if (fallback == Fallback::none) return {};
  if (const auto h = registry.column_orientation(series.column)) return {h->first, h->second};
  return {true, "assumed: not a registered metric"};
}

}  // namespace qm3d::evaluation
