#include "qm3d/evaluation/training.h"

#include <Eigen/Core>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

#include "least_squares.h"
#include "qm3d/common/error.h"
#include "qm3d/common/pooling.h"
#include "qm3d/common/statistics.h"
#include "qm3d/evaluation/model_io.h"

namespace qm3d::evaluation {
namespace {

/// Fewest stimuli in a held-out group: a correlation over fewer says nothing.
constexpr std::size_t kMinRowsPerGroup = 3;
/// Rows needed beyond the parameters of the link fit (#subset weights + c + beta1 + beta2).
constexpr std::size_t kExtraRowsForFit = 2;

std::vector<std::size_t> subset_indices(FeatureMask subset) {
  if (subset == 0 || subset > kAllFeatures) {
    throw std::invalid_argument("feature subset " + std::to_string(subset) + " not in 1..255");
  }
  std::vector<std::size_t> cols;
  for (std::size_t k = 0; k < kNumFeatures; ++k) {
    if (subset & (1u << k)) cols.push_back(k);
  }
  return cols;
}

// The subset's features, each column standardised (z-scores), and the standardised MOS.
struct Standardised {
  Eigen::MatrixXd z;  // #n by #subset
  std::vector<double> feature_mean, feature_sd;
  std::vector<double> y;  // #n
  double y_mean = 0, y_sd = 0;
};

Standardised standardise(const std::vector<FeatureVector>& features, const std::vector<double>& mos,
                         const std::vector<std::size_t>& cols) {
  Standardised s;
  const auto n = static_cast<Eigen::Index>(features.size());
  s.z.resize(n, static_cast<Eigen::Index>(cols.size()));
  for (std::size_t c = 0; c < cols.size(); ++c) {
    std::vector<double> column;
    for (const FeatureVector& f : features) column.push_back(f[cols[c]]);
    const double mean = mean_pool(column), sd = population_sd(column, mean);
    if (!std::isfinite(mean) || !std::isfinite(sd)) {
      // Values near 1e300: the squares overflow; every z would be 0 ("constant" further on).
      throw NumericError("feature " + feature_name(cols[c]) +
                         " has values too large to standardise (its mean or standard deviation "
                         "overflows a double)");
    }
    if (!(sd > 0)) throw NumericError("feature " + feature_name(cols[c]) + " is constant");
    for (Eigen::Index i = 0; i < n; ++i) s.z(i, c) = (column[i] - mean) / sd;
    s.feature_mean.push_back(mean);
    s.feature_sd.push_back(sd);
  }
  s.y_mean = mean_pool(mos);
  s.y_sd = population_sd(mos, s.y_mean);
  if (!std::isfinite(s.y_mean) || !std::isfinite(s.y_sd)) {
    throw NumericError(
        "the subjective scores are too large to standardise (their mean or "
        "standard deviation overflows a double)");
  }
  if (!(s.y_sd > 0)) throw NumericError("the subjective scores are constant");
  for (double m : mos) s.y.push_back((m - s.y_mean) / s.y_sd);
  return s;
}

// Parameters (beta1, beta2, a_1..a_m, c) of y ~ beta2 + (beta1 - beta2) sigma(z a + c).
detail::LeastSquaresProblem link_problem(const Standardised& s) {
  detail::LeastSquaresProblem p;
  p.residuals = s.z.rows();
  const Eigen::Index m = s.z.cols();
  p.residual = [&s, m](const Eigen::VectorXd& x, Eigen::VectorXd& r) {
    const Eigen::VectorXd t = s.z * x.segment(2, m);
    for (Eigen::Index i = 0; i < r.size(); ++i) {
      r[i] = x[1] + (x[0] - x[1]) * detail::logistic_sigmoid(t[i] + x[m + 2]) - s.y[i];
    }
  };
  p.jacobian = [&s, m](const Eigen::VectorXd& x, Eigen::MatrixXd& jac) {
    const Eigen::VectorXd t = s.z * x.segment(2, m);
    for (Eigen::Index i = 0; i < jac.rows(); ++i) {
      const double sg = detail::logistic_sigmoid(t[i] + x[m + 2]);
      const double slope = (x[0] - x[1]) * sg * (1 - sg);  // d y / d t
      jac(i, 0) = sg;
      jac(i, 1) = 1 - sg;
      jac.row(i).segment(2, m) = slope * s.z.row(i);
      jac(i, m + 2) = slope;
    }
  };
  // The scale along the standardised features is 1 / |a|.
  p.admissible = [m](const Eigen::VectorXd& x) {
    return detail::logistic_admissible(x[0], x[1], 1 / x.segment(2, m).norm());
  };
  return p;
}

// Start: the least-squares linear direction, then a 1-D logistic fit along it.
Eigen::VectorXd link_start(const Standardised& s, const LogisticFitOptions& options) {
  const Eigen::Index n = s.z.rows(), m = s.z.cols();
  Eigen::MatrixXd design(n, m + 1);
  design << Eigen::VectorXd::Ones(n), s.z;
  const Eigen::Map<const Eigen::VectorXd> y(s.y.data(), n);
  const Eigen::VectorXd linear = design.colPivHouseholderQr().solve(y);
  const Eigen::VectorXd direction = linear.tail(m);
  const Eigen::VectorXd t = s.z * direction;
  const LogisticFit along = fit_logistic(std::vector<double>(t.data(), t.data() + n), s.y, options);
  const double scale = std::fabs(along.function.beta4);
  Eigen::VectorXd x(m + 3);
  x << along.function.beta1, along.function.beta2, direction / scale, -along.function.beta3 / scale;
  return x;
}

// Back to raw feature units: weights with sum |w| = 1 that grow with distortion, and the
// decreasing VQEG logistic of the score w . f (see training.h).
LinkFit to_link_fit(const Eigen::VectorXd& x, const Standardised& s,
                    const std::vector<std::size_t>& cols) {
  const Eigen::Index m = s.z.cols();
  double offset = x[m + 2], norm = 0;
  std::vector<double> raw(cols.size());
  for (std::size_t c = 0; c < cols.size(); ++c) {
    raw[c] = x[2 + static_cast<Eigen::Index>(c)] / s.feature_sd[c];
    offset -= raw[c] * s.feature_mean[c];
    norm += std::fabs(raw[c]);
  }
  if (!(norm > 0) || !std::isfinite(norm)) throw NumericError("link fit: every weight is 0");
  const double sign = x[0] < x[1] ? 1.0 : -1.0;  // y decreasing in t -> keep the direction
  LinkFit fit;
  for (std::size_t c = 0; c < cols.size(); ++c) fit.weights[cols[c]] = sign * raw[c] / norm;
  const double slope = sign * norm;  // t = slope * score + offset
  const double low = s.y_mean + s.y_sd * std::min(x[0], x[1]);
  const double high = s.y_mean + s.y_sd * std::max(x[0], x[1]);
  fit.mos_mapping = {low, high, -offset / slope, 1.0 / norm};
  return fit;
}

std::vector<double> scores_of(const std::vector<FeatureVector>& features,
                              const FeatureVector& weights) {
  std::vector<double> scores;
  scores.reserve(features.size());
  for (const FeatureVector& f : features) {
    double s = 0;
    for (std::size_t k = 0; k < kNumFeatures; ++k) s += weights[k] * f[k];
    scores.push_back(s);
  }
  return scores;
}

// ---- cross-validation ----------------------------------------------------------------------

struct Fold {
  std::string name;
  std::vector<std::size_t> train, test;
};

std::vector<Fold> folds_of(const Grouping& g) {
  std::vector<std::string> labels;  // first-appearance order
  std::map<std::string, std::size_t> index;
  for (const std::string& label : g.labels) {
    if (index.emplace(label, labels.size()).second) labels.push_back(label);
  }
  if (labels.size() < 2) {
    throw NumericError("grouping \"" + g.name + "\" has " + std::to_string(labels.size()) +
                       " group; leave-one-group-out needs at least 2");
  }
  std::vector<Fold> folds(labels.size());
  for (std::size_t f = 0; f < labels.size(); ++f) folds[f].name = g.name + "=" + labels[f];
  for (std::size_t i = 0; i < g.labels.size(); ++i) {
    const std::size_t own = index.at(g.labels[i]);
    for (std::size_t f = 0; f < folds.size(); ++f)
      (f == own ? folds[f].test : folds[f].train).push_back(i);
  }
  for (const Fold& f : folds) {
    if (f.test.size() < kMinRowsPerGroup) {
      throw NumericError("group " + f.name + " has " + std::to_string(f.test.size()) +
                         " rows; leave-one-group-out needs at least " +
                         std::to_string(kMinRowsPerGroup));
    }
  }
  return folds;
}

template <typename T>
std::vector<T> pick(const std::vector<T>& v, const std::vector<std::size_t>& rows) {
  std::vector<T> out;
  out.reserve(rows.size());
  for (std::size_t i : rows) out.push_back(v[i]);
  return out;
}

struct FoldResult {
  FeatureVector weights{};
  double plcc = 0, srocc = 0;
};

double defined_or_zero(double correlation) { return std::isfinite(correlation) ? correlation : 0; }

FoldResult run_fold(const TrainingSet& data, const Fold& fold, FeatureMask subset,
                    const LogisticFitOptions& options) {
  const LinkFit fit = fit_logistic_link(pick(data.features, fold.train), pick(data.mos, fold.train),
                                        subset, options);
  const std::vector<double> scores = scores_of(pick(data.features, fold.test), fit.weights);
  const std::vector<double> mos = pick(data.mos, fold.test);
  std::vector<double> predicted;
  for (double s : scores) predicted.push_back(fit.mos_mapping(s));
  // The mapping is decreasing, so the ranks of the prediction are those of -score.
  return {fit.weights, defined_or_zero(pearson(predicted, mos)),
          defined_or_zero(-spearman(scores, mos))};
}

std::pair<double, double> mean_and_sd(const std::vector<double>& v) {
  const double mean = mean_pool(v);
  if (v.size() < 2) return {mean, 0.0};
  double sum = 0;
  for (double x : v) sum += (x - mean) * (x - mean);
  return {mean, std::sqrt(sum / static_cast<double>(v.size() - 1))};
}

SubsetScore score_subset(const TrainingSet& data, const std::vector<Fold>& folds,
                         FeatureMask subset, const LogisticFitOptions& options) {
  SubsetScore score;
  score.subset = subset;
  try {
    for (const Fold& fold : folds) {
      const FoldResult r = run_fold(data, fold, subset, options);
      score.fold_plcc.push_back(r.plcc);
      score.fold_srocc.push_back(r.srocc);
    }
  } catch (const NumericError& e) {
    score.error = e.what();
    score.fold_plcc.clear();
    score.fold_srocc.clear();
    return score;
  }
  std::tie(score.plcc_mean, score.plcc_sd) = mean_and_sd(score.fold_plcc);
  std::tie(score.srocc_mean, score.srocc_sd) = mean_and_sd(score.fold_srocc);
  return score;
}

// ---- ranking and the final model -----------------------------------------------------------

double criterion_value(const SubsetScore& s, SubsetCriterion c) {
  switch (c) {
    case SubsetCriterion::kPlcc:
      return s.plcc_mean;
    case SubsetCriterion::kSrocc:
      return s.srocc_mean;
    case SubsetCriterion::kPlccAndSrocc:
      return 0.5 * (s.plcc_mean + s.srocc_mean);
  }
  return s.plcc_mean;
}

// Standard error over the folds of the criterion.
double criterion_standard_error(const SubsetScore& s, SubsetCriterion c) {
  std::vector<double> per_fold;
  for (std::size_t f = 0; f < s.fold_plcc.size(); ++f) {
    const double p = s.fold_plcc[f], r = s.fold_srocc[f];
    per_fold.push_back(c == SubsetCriterion::kPlcc    ? p
                       : c == SubsetCriterion::kSrocc ? r
                                                      : 0.5 * (p + r));
  }
  return mean_and_sd(per_fold).second / std::sqrt(static_cast<double>(per_fold.size()));
}

double tie_break_value(const SubsetScore& s, SubsetCriterion c) {
  return c == SubsetCriterion::kSrocc ? s.plcc_mean : s.srocc_mean;
}

int feature_count(FeatureMask m) { return static_cast<int>(subset_indices(m).size()); }

void rank_subsets(std::vector<SubsetScore>& scores, SubsetCriterion c) {
  std::stable_sort(scores.begin(), scores.end(), [c](const SubsetScore& a, const SubsetScore& b) {
    if (a.error.empty() != b.error.empty()) return a.error.empty();
    if (!a.error.empty()) return a.subset < b.subset;
    if (criterion_value(a, c) != criterion_value(b, c)) {
      return criterion_value(a, c) > criterion_value(b, c);
    }
    if (tie_break_value(a, c) != tie_break_value(b, c)) {
      return tie_break_value(a, c) > tie_break_value(b, c);
    }
    if (feature_count(a.subset) != feature_count(b.subset)) {
      return feature_count(a.subset) < feature_count(b.subset);
    }
    return a.subset < b.subset;
  });
}

// The chosen subset of a ranking whose front is the best (see SubsetSelection).
FeatureMask select_subset(const std::vector<SubsetScore>& ranked, const TrainingOptions& o) {
  const SubsetScore& best = ranked.front();
  if (o.selection == SubsetSelection::kBest) return best.subset;
  const double threshold =
      criterion_value(best, o.criterion) - criterion_standard_error(best, o.criterion);
  FeatureMask chosen = best.subset;
  for (const SubsetScore& s : ranked) {  // best first: the first of the fewest features wins
    if (!s.error.empty() || criterion_value(s, o.criterion) < threshold) continue;
    if (feature_count(s.subset) < feature_count(chosen)) chosen = s.subset;
  }
  return chosen;
}

// Mean of the folds' weights, renormalised to sum |w| = 1, and the mapping refitted on all rows.
LinkFit mean_of_folds(const TrainingSet& data, const std::vector<Fold>& folds, FeatureMask subset,
                      const LogisticFitOptions& options) {
  FeatureVector sum{};
  for (const Fold& fold : folds) {
    const FoldResult r = run_fold(data, fold, subset, options);
    for (std::size_t k = 0; k < kNumFeatures; ++k) sum[k] += r.weights[k];
  }
  double norm = 0;
  for (double w : sum) norm += std::fabs(w);
  if (!(norm > 0)) return fit_logistic_link(data.features, data.mos, subset, options);
  LinkFit fit;
  for (std::size_t k = 0; k < kNumFeatures; ++k) fit.weights[k] = sum[k] / norm;
  const LogisticFit mapping =
      fit_logistic(scores_of(data.features, fit.weights), data.mos, options);
  fit.mos_mapping = mapping.function;
  fit.rmse = mapping.rmse;
  fit.converged = mapping.converged;
  fit.bounded = mapping.bounded;
  return fit;
}

void check_training_set(const TrainingSet& data) {
  if (data.features.size() != data.mos.size()) {
    throw std::invalid_argument("training: features and MOS differ in length");
  }
  if (data.groupings.empty()) throw std::invalid_argument("training: no grouping given");
  for (const Grouping& g : data.groupings) {
    if (g.labels.size() != data.mos.size()) {
      throw std::invalid_argument("training: grouping \"" + g.name + "\" has the wrong length");
    }
  }
  for (std::size_t i = 0; i < data.mos.size(); ++i) {
    const FeatureVector& f = data.features[i];
    const bool finite = std::all_of(f.begin(), f.end(), [](double v) { return std::isfinite(v); });
    if (!finite || !std::isfinite(data.mos[i])) {
      throw NumericError("training: non-finite value in row " + std::to_string(i + 1));
    }
  }
}

std::vector<Fold> all_folds(const TrainingSet& data) {
  std::vector<Fold> folds;
  for (const Grouping& g : data.groupings) {
    for (Fold& f : folds_of(g)) folds.push_back(std::move(f));
  }
  return folds;
}

std::vector<FeatureMask> subsets_to_search(const TrainingOptions& options) {
  if (!options.subsets.empty()) return options.subsets;
  std::vector<FeatureMask> all;
  for (FeatureMask m = 1; m <= kAllFeatures; ++m) all.push_back(m);
  return all;
}

}  // namespace

std::string subset_name(FeatureMask subset) {
  std::string out;
  for (std::size_t k : subset_indices(subset)) out += (out.empty() ? "" : ",") + feature_name(k);
  return out;
}

FeatureMask parse_subset(const std::string& names) {
  FeatureMask mask = 0;
  std::istringstream in(names);
  std::string name;
  while (std::getline(in, name, ',')) {
    name.erase(0, name.find_first_not_of(' '));
    name.erase(name.find_last_not_of(' ') + 1);
    mask |= 1u << feature_index(name);
  }
  if (mask == 0) throw FormatError("empty feature subset \"" + names + "\"");
  return mask;
}

LinkFit fit_logistic_link(const std::vector<FeatureVector>& features,
                          const std::vector<double>& mos, FeatureMask subset,
                          const LogisticFitOptions& options) {
  if (features.size() != mos.size()) {
    throw std::invalid_argument("link fit: features and MOS differ in length");
  }
  const std::vector<std::size_t> cols = subset_indices(subset);
  if (features.size() < cols.size() + 3 + kExtraRowsForFit) {
    throw NumericError("link fit: " + std::to_string(features.size()) + " rows for " +
                       std::to_string(cols.size()) + " features");
  }
  const Standardised s = standardise(features, mos, cols);
  const detail::LeastSquaresResult r = detail::minimize_least_squares(
      link_problem(s), link_start(s, options), options.max_evaluations, options.tolerance);
  if (!r.x.allFinite()) throw NumericError("link fit: no finite optimum");
  LinkFit fit = to_link_fit(r.x, s, cols);
  fit.rmse = s.y_sd * std::sqrt(r.sum_squares / static_cast<double>(mos.size()));
  fit.converged = r.converged;
  fit.bounded = r.left_region;
  return fit;
}

TrainingResult train_linear_model(const TrainingSet& data, const TrainingOptions& options) {
  check_training_set(data);
  const std::vector<Fold> folds = all_folds(data);
  TrainingResult result;
  for (FeatureMask m : subsets_to_search(options)) {
    result.subsets.push_back(score_subset(data, folds, m, options.fit));
  }
  rank_subsets(result.subsets, options.criterion);
  const SubsetScore& best = result.subsets.front();
  if (!best.error.empty()) {
    throw NumericError("training: no feature subset could be fitted (" + subset_name(best.subset) +
                       ": " + best.error + ")");
  }
  result.best = select_subset(result.subsets, options);
  result.model = options.final_weights == FinalWeights::kRefit
                     ? fit_logistic_link(data.features, data.mos, result.best, options.fit)
                     : mean_of_folds(data, folds, result.best, options.fit);
  for (const Fold& f : folds) result.folds.push_back(f.name);
  return result;
}

}  // namespace qm3d::evaluation
