// Pooling of per-element values into one score, and linear feature models.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "qm3d/common/features.h"

namespace qm3d {

/// Arithmetic mean, summed sequentially in element order (deterministic). Empty -> 0.
double mean_pool(const std::vector<double>& values);

/// Minkowski pooling (sum |x|^p / n)^(1/p), summed in element order (MSDM2 uses p = 3).
double minkowski_pool(const std::vector<double>& values, double p);

/// Component-wise mean of per-element feature vectors, summed in element order.
FeatureVector mean_features(const FeatureVector* per_element, std::size_t count);
inline FeatureVector mean_features(const std::vector<FeatureVector>& per_element) {
  return mean_features(per_element.data(), per_element.size());
}

/// MEPP-team/PCQM's pooling (`write_mean_features`): from per-element f1..f3 and s4..s8 (the
/// similarities, features.h local_features_and_similarities), F1..F3 = (sum f) / n and
/// F4..F8 = 1 - (sum s) / n, summed in element order. Differs from mean_features of 1 - s by
/// rounding only (about 1e-14 absolute), visible on near-zero scores. Empty -> all 0.
FeatureVector mean_features_from_similarities(const FeatureVector* per_element, std::size_t count);
inline FeatureVector mean_features_from_similarities(
    const std::vector<FeatureVector>& per_element) {
  return mean_features_from_similarities(per_element.data(), per_element.size());
}

/// A metric's score as a weighted sum of its (pooled) features.
struct LinearModel {
  std::string metric;       ///< "cmdm", "pcqm", ...
  FeatureVector weights{};  ///< weight of f1..f8
  std::string provenance;   ///< where the weights come from

  double apply(const FeatureVector& features) const;
};

/// CMDM: 0.091 f2 + 0.22 f5 + 0.032 f6 + 0.656 f7 (CMDM paper eq. 1.13; MEPP2 cmdm.h).
const LinearModel& cmdm_model();
/// PCQM: 0.0057 F3 + 0.9771 F4 + 0.0172 F6 (PCQM paper; MEPP-team/PCQM main.cpp).
const LinearModel& pcqm_model();

}  // namespace qm3d
