#include "qm3d/common/result.h"

#include <stdexcept>

namespace qm3d {

std::string direction_name(Direction d) {
  switch (d) {
    case Direction::kSymmetric: return "symmetric";
    case Direction::kDistToRef: return "dist-to-ref";
    case Direction::kRefToDist: return "ref-to-dist";
  }
  return "?";
}

Direction parse_direction(const std::string& name) {
  for (const Direction d : {Direction::kSymmetric, Direction::kDistToRef, Direction::kRefToDist}) {
    if (name == direction_name(d)) return d;
  }
  throw std::invalid_argument("unknown direction '" + name +
                              "' (expected symmetric, dist-to-ref or ref-to-dist)");
}

const DirectionResult& MetricResult::any_direction(bool prefer_dist) const {
  if (dist_to_ref && (prefer_dist || !ref_to_dist)) return *dist_to_ref;
  if (ref_to_dist) return *ref_to_dist;
  throw std::logic_error(metric + ": the result has no direction");
}

Direction MetricResult::direction() const {
  if (dist_to_ref && ref_to_dist) return Direction::kSymmetric;
  return dist_to_ref ? Direction::kDistToRef : Direction::kRefToDist;
}

std::vector<std::string> feature_names(const std::string& prefix) {
  std::vector<std::string> names;
  for (std::size_t k = 1; k <= kNumFeatures; ++k) names.push_back(prefix + std::to_string(k));
  return names;
}

void combine_directions(MetricResult& result) {
  if (result.dist_to_ref && result.ref_to_dist) {
    result.score = (result.dist_to_ref->score + result.ref_to_dist->score) / 2;
  } else {
    result.score = result.any_direction().score;
  }
}

std::optional<double> find_value(const NamedValues& values, const std::string& name) {
  for (const auto& [n, v] : values) {
    if (n == name) return v;
  }
  return std::nullopt;
}

}  // namespace qm3d
