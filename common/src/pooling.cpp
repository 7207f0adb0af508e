#include "qm3d/common/pooling.h"

#include <cmath>

namespace qm3d {

double mean_pool(const std::vector<double>& values) {
  if (values.empty()) return 0.0;
  double sum = 0;
  for (double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

double minkowski_pool(const std::vector<double>& values, double p) {
  if (values.empty()) return 0.0;
  double sum = 0;
  for (double v : values) sum += std::pow(std::fabs(v), p);
  return std::pow(sum / static_cast<double>(values.size()), 1.0 / p);
}

FeatureVector mean_features(const FeatureVector* per_element, std::size_t count) {
  FeatureVector sum{};
  for (std::size_t i = 0; i < count; ++i) {
    for (std::size_t k = 0; k < kNumFeatures; ++k) sum[k] += per_element[i][k];
  }
  if (count == 0) return sum;
  for (auto& s : sum) s /= static_cast<double>(count);
  return sum;
}

FeatureVector mean_features_from_similarities(const FeatureVector* per_element, std::size_t count) {
  if (count == 0) return FeatureVector{};
  FeatureVector pooled = mean_features(per_element, count);
  similarities_to_features(pooled);
  return pooled;
}

double LinearModel::apply(const FeatureVector& features) const {
  double score = 0;
  for (std::size_t k = 0; k < kNumFeatures; ++k) {
    if (weights[k] != 0.0) score += weights[k] * features[k];
  }
  return score;
}

const LinearModel& cmdm_model() {
  static const LinearModel model{
      "cmdm",
      {0, 0.091, 0, 0, 0.22, 0.032, 0.656, 0},
      "Nehme et al., CMDM, eq. 1.13 (logistic regression on the vertex-colour dataset); "
      "MEPP2 cmdm.h w2, w5, w6, w7"};
  return model;
}

const LinearModel& pcqm_model() {
  static const LinearModel model{
      "pcqm",
      {0, 0, 0.0057, 0.9771, 0, 0.0172, 0, 0},
      "Meynet et al., PCQM, QoMEX 2020; MEPP-team/PCQM main.cpp `PCQM Formula`"};
  return model;
}

}  // namespace qm3d
