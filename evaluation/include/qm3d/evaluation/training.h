// Training the weights of a linear feature model against subjective scores, as the CMDM report
// does (Nehme et al., CMDM, §1.2.5 and §1.3.1: weights "obtained through an optimization
// computed by logistic regression", feature subset chosen among all 255 by leave-one-out
// cross-validation over source models and over distortion types, the recommended weights being
// the mean of the folds' weights, §1.3.3):
//
//   MOS_i ~ beta2 + (beta1 - beta2) * sigma(sum_k a_k f_ik + c),   sigma(t) = 1 / (1 + e^-t)
//
// fitted by nonlinear least squares over a, c, beta1, beta2 jointly (Levenberg-Marquardt, Eigen),
// started from the least-squares linear fit and a 1-D logistic fit along it. The weights are a
// rescaled so that sum_k |w_k| = 1 with the sign that makes the score w . f grow as the MOS
// falls (a distortion, like CMDM and PCQM, whose published weights also sum to 1).
//
// Feature subsets are compared by leave-one-group-out cross-validation (a group = a source model
// or a distortion type, so that no stimulus of the held-out group helps choose the weights).
// Several groupings may be given: their folds are pooled (the report's 5 + 4 = 9 folds).
//
// Example:
//   qm3d::TrainingSet data{features, mos, {{"source", source_of_each_row}}};
//   const qm3d::TrainingResult r = qm3d::train_linear_model(data);
//   // r.best: the chosen subset (see SubsetSelection); r.model.weights: its weights
#pragma once

#include <string>
#include <vector>

#include "qm3d/evaluation/evaluation.h"
#include "qm3d/common/features.h"

namespace qm3d::evaluation {

/// A set of features: bit k set = f(k+1) used. 1..255.
using FeatureMask = unsigned;
inline constexpr FeatureMask kAllFeatures = (1u << kNumFeatures) - 1;

/// "f2,f5,f7".
std::string subset_name(FeatureMask subset);
/// "f2,f5,f7" (or "F2, f5") -> mask. @throws FormatError on an unknown name or an empty list.
FeatureMask parse_subset(const std::string& names);

/// One way of splitting the stimuli into cross-validation groups.
struct Grouping {
  std::string name;                 ///< e.g. the column it comes from ("Source_model")
  std::vector<std::string> labels;  ///< #n group of each stimulus
};

struct TrainingSet {
  std::vector<FeatureVector> features;  ///< #n pooled features f1..f8 of each stimulus
  std::vector<double> mos;              ///< #n subjective scores
  std::vector<Grouping> groupings;      ///< one or more; each held-out group is one fold
};

/// The logistic-link regression on one feature subset.
struct LinkFit {
  FeatureVector weights{};       ///< sum |w_k| = 1; 0 outside the subset
  LogisticFunction mos_mapping;  ///< MOS ~ mos_mapping(weights . f), decreasing
  double rmse = 0;               ///< of the mapped scores against the MOS (MOS units)
  bool converged = false;        ///< Levenberg-Marquardt met its tolerances
  bool bounded = false;          ///< stopped at the asymptote bound (see LogisticFit::bounded)
};

/// Fits the weights of `subset` on all rows of `features` and `mos`.
/// @throws NumericError  fewer rows than the fit needs, a feature of the subset or the MOS
///                       constant, or no finite optimum
/// @throws std::invalid_argument  lengths differ, or subset not in 1..255
LinkFit fit_logistic_link(const std::vector<FeatureVector>& features,
                          const std::vector<double>& mos, FeatureMask subset,
                          const LogisticFitOptions& options = {});

/// Held-out agreement of one subset over the cross-validation folds.
struct SubsetScore {
  FeatureMask subset = 0;
  /// Mean and sample standard deviation over the folds of PLCC(mapping(w . f), MOS) and
  /// SROCC(mapping(w . f), MOS) on each held-out group, with w and the mapping fitted on the
  /// other groups. A fold whose correlation is undefined (constant prediction) counts as 0.
  double plcc_mean = 0, plcc_sd = 0;
  double srocc_mean = 0, srocc_sd = 0;
  std::vector<double> fold_plcc, fold_srocc;  ///< per fold, in TrainingResult::folds order
  /// Why the subset could not be fitted (e.g. a constant feature); empty on success.
  std::string error;
};

/// How the subsets are ranked.
enum class SubsetCriterion {
  kPlcc,         ///< mean PLCC (then mean SROCC)
  kSrocc,        ///< mean SROCC (then mean PLCC)
  kPlccAndSrocc  ///< (mean PLCC + mean SROCC) / 2
};

/// How the subset is chosen from the ranking.
enum class SubsetSelection {
  /// The fewest features among the subsets whose criterion is within one standard error (over
  /// the folds) of the best one ("one-standard-error rule", Hastie, Tibshirani & Friedman, The
  /// Elements of Statistical Learning, 2nd ed., §7.10): a superset that wins by noise alone
  /// does not displace the true subset.
  kOneStandardError,
  /// The best criterion, as the CMDM report words it.
  kBest
};

/// Which weights the chosen subset finally gets.
enum class FinalWeights {
  kMeanOfFolds,  ///< mean of the folds' weights (the CMDM report §1.3.3), mapping refitted;
                 ///< a refit when the folds' weights cancel out
  kRefit         ///< one more fit on every row
};

struct TrainingOptions {
  /// Subsets to compare; empty = all 255 non-empty subsets of f1..f8.
  std::vector<FeatureMask> subsets;
  SubsetCriterion criterion = SubsetCriterion::kPlcc;
  SubsetSelection selection = SubsetSelection::kOneStandardError;
  FinalWeights final_weights = FinalWeights::kMeanOfFolds;
  LogisticFitOptions fit;
};

struct TrainingResult {
  /// Best first by the criterion, then fewer features, then lower mask; the subsets that
  /// failed come last (by mask).
  std::vector<SubsetScore> subsets;
  FeatureMask best = 0;            ///< the chosen subset (see SubsetSelection)
  LinkFit model;                   ///< the final weights of `best` and their mapping on every row
  std::vector<std::string> folds;  ///< "grouping=label" of each fold, groupings in order, labels
                                   ///< in order of first appearance
};

/// Exhaustive subset search with leave-one-group-out cross-validation, then the final fit.
/// @throws NumericError  a grouping with fewer than 2 groups, a group with fewer than 3 rows, a
///                       non-finite value, or no subset could be fitted
/// @throws std::invalid_argument  lengths differ, no grouping, or a subset is not in 1..255
TrainingResult train_linear_model(const TrainingSet& data, const TrainingOptions& options = {});

}  // namespace qm3d::evaluation
