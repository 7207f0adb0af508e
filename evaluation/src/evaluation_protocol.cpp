#include "qm3d/evaluation/evaluation_protocol.h"

#include <cmath>
#include <stdexcept>

#include "qm3d/evaluation/evaluation_io.h"

namespace qm3d::evaluation {
namespace {

using ordered_json = nlohmann::ordered_json;

ordered_json number(double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(); }

ordered_json statistics_json(const EvaluationResult& r, const P1401Statistics& p) {
  ordered_json s = {{"plcc", statistic_json(r.plcc)},
                    {"srocc", statistic_json(r.srocc)},
                    {"krocc", statistic_json(r.krocc)},
                    {"plcc_mapped", statistic_json(p.plcc)},
                    {"rmse_mapped", statistic_json(p.rmse)}};
  if (p.rmse_star) s["rmse_star"] = statistic_json(*p.rmse_star);
  if (p.outlier_ratio) s["outlier_ratio"] = statistic_json(*p.outlier_ratio);
  return s;
}

ordered_json mapping_json(const P1401Evaluation& p) {
  const MappingFit& f = p.fit;
  ordered_json j = {{"name", std::string(mapping_name(f.function.mapping))},
                    {"parameters", ordered_json::array()},
                    {"parameter_count", f.parameter_count},
                    {"degrees_of_freedom", p.statistics.degrees_of_freedom},
                    {"converged", f.converged},
                    {"bounded", f.bounded},
                    {"constrained", f.constrained}};
  for (double v : f.function.parameters) j["parameters"].push_back(number(v));
  return j;
}

ordered_json krasula_metric_json(const KrasulaMetric& m, const KrasulaResult& r) {
  return {{"auc_ds", number(m.auc_ds)},
          {"auc_bw", number(m.auc_bw)},
          {"c0", number(m.c0)},
          {"thr", number(m.thr_numpy)},
          {"thr_prctile", number(m.thr_prctile)},
          {"se_ds", number(m.se_ds)},
          {"se_bw", number(m.se_bw)},
          {"different", r.different},
          {"similar", r.similar}};
}

ordered_json comparison(const std::string& a, const std::string& b, const char* test, double z,
                        double p) {
  return {{"a", a}, {"b", b}, {"test", test}, {"statistic", number(z)}, {"p", number(p)}};
}

}  // namespace

ProtocolResult run_protocol(const std::vector<MetricScores>& metrics,
                            const SubjectiveData& subjective, const ProtocolOptions& options) {
  if (metrics.empty()) throw std::invalid_argument("evaluation: no metric");
  for (std::size_t i = 0; i < metrics.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (metrics[i].name == metrics[j].name) {
        throw std::invalid_argument("evaluation: metric \"" + metrics[i].name + "\" given twice");
      }
    }
  }
  ProtocolResult r;
  // The protocol reports the correlations of evaluate_scores, not its logistic: with --mapping
  // none or linear, 3 or 4 stimuli are enough (VMAF's own tests have 4).
  EvaluationOptions evaluation = options.evaluation;
  evaluation.require_logistic = false;
  for (const MetricScores& m : metrics) {
    r.evaluations.push_back(evaluate_scores(m.scores, subjective.mos, subjective.ci95, evaluation));
    r.p1401.push_back(evaluate_p1401(m.scores, subjective.mos, options.mapping, subjective.ci95,
                                     options.evaluation.fit));
  }
  if (subjective.pairs) {
    // Krasula's differences are oriented higher = better: a distortion's scores are negated.
    std::vector<std::vector<double>> oriented;
    for (const MetricScores& m : metrics) {
      oriented.push_back(m.scores);
      if (!m.higher_is_better) {
        for (double& s : oriented.back()) s = -s;
      }
    }
    r.krasula = krasula_analysis(oriented, *subjective.pairs);
  }
  return r;
}

ordered_json protocol_json(const std::vector<MetricScores>& metrics,
                           const SubjectiveData& subjective, const ProtocolResult& r) {
  ordered_json out;
  out["stimuli"] = subjective.mos.size();
  ordered_json per_metric = ordered_json::object();
  for (std::size_t i = 0; i < metrics.size(); ++i) {
    const EvaluationResult& e = r.evaluations[i];
    ordered_json j;
    j["orientation"] = {{"higher_is_better", metrics[i].higher_is_better},
                        {"from", metrics[i].orientation_source}};
    j["statistics"] = statistics_json(e, r.p1401[i].statistics);
    j["mapping"] = mapping_json(r.p1401[i]);
    j["bootstrap"] = {{"replicates", e.bootstrap_replicates}, {"used", e.bootstrap_used}};
    j["krasula"] =
        r.krasula ? krasula_metric_json(r.krasula->metrics[i], *r.krasula) : ordered_json();
    per_metric[metrics[i].name] = std::move(j);
  }
  out["metrics"] = std::move(per_metric);
  out["krasula"] = nullptr;
  out["comparisons"] = ordered_json::array();
  for (std::size_t a = 0; a < metrics.size(); ++a) {
    for (std::size_t b = a + 1; b < metrics.size(); ++b) {
      const P1401Comparison c = compare_p1401(r.p1401[a].statistics, r.p1401[b].statistics);
      const std::string& na = metrics[a].name;
      const std::string& nb = metrics[b].name;
      out["comparisons"].push_back(comparison(na, nb, "fisher_z_plcc", c.plcc.statistic, c.plcc.p));
      out["comparisons"].push_back(comparison(na, nb, "f_rmse", c.rmse.statistic, c.rmse.p));
      if (c.rmse_star) {
        out["comparisons"].push_back(
            comparison(na, nb, "f_rmse_star", c.rmse_star->statistic, c.rmse_star->p));
      }
      if (c.outlier_ratio) {
        out["comparisons"].push_back(
            comparison(na, nb, "outlier_ratio", c.outlier_ratio->statistic, c.outlier_ratio->p));
      }
    }
  }
  if (r.krasula) {
    const KrasulaResult& k = *r.krasula;
    out["krasula"] = {{"rule", subjective.pairs->rule},
                      {"pairs", subjective.pairs->size()},
                      {"different", k.different},
                      {"better", k.better},
                      {"similar", k.similar},
                      {"orientation", "differences of scores oriented higher = better (a "
                                      "distortion's negated)"}};
    for (const KrasulaComparison& c : k.comparisons) {
      const std::string& a = metrics[c.a].name;
      const std::string& b = metrics[c.b].name;
      out["comparisons"].push_back(comparison(a, b, "delong_auc_ds", c.z_delong_ds, c.p_delong_ds));
      out["comparisons"].push_back(comparison(a, b, "delong_auc_bw", c.z_delong_bw, c.p_delong_bw));
      out["comparisons"].push_back(comparison(a, b, "c0", c.z_c0, c.p_c0));
    }
  }
  return out;
}

ordered_json evaluate_metrics(const std::vector<MetricScores>& metrics,
                              const SubjectiveData& subjective, const ProtocolOptions& options) {
  return protocol_json(metrics, subjective, run_protocol(metrics, subjective, options));
}

}  // namespace qm3d::evaluation
