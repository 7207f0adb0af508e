#include "qm3d/evaluation/evaluation_io.h"

#include <cmath>

namespace qm3d::evaluation {
namespace {

using ordered_json = nlohmann::ordered_json;

ordered_json number(double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(); }

}  // namespace

ordered_json statistic_json(const Statistic& s) {
  ordered_json j = {{"value", number(s.value)}, {"ci95", nullptr}};
  if (s.ci) j["ci95"] = {number(s.ci->low), number(s.ci->high)};
  return j;
}

std::vector<std::pair<std::string, Statistic>> named_statistics(const EvaluationResult& r) {
  std::vector<std::pair<std::string, Statistic>> s = {{"plcc", r.plcc},
                                                      {"srocc", r.srocc},
                                                      {"krocc", r.krocc},
                                                      {"plcc_logistic", r.plcc_logistic},
                                                      {"rmse_logistic", r.rmse_logistic}};
  if (r.outlier_ratio) s.emplace_back("outlier_ratio", *r.outlier_ratio);
  return s;
}

ordered_json logistic_json(const LogisticFit& fit) {
  return {{"function", "beta2 + (beta1 - beta2) / (1 + exp(-(x - beta3) / |beta4|))"},
          {"beta1", number(fit.function.beta1)},
          {"beta2", number(fit.function.beta2)},
          {"beta3", number(fit.function.beta3)},
          {"beta4", number(fit.function.beta4)},
          {"rmse", number(fit.rmse)},
          {"converged", fit.converged},
          {"bounded", fit.bounded}};
}

}  // namespace qm3d::evaluation
