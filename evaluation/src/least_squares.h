// Private: nonlinear least squares through Eigen's Levenberg-Marquardt (the MINPACK lmder port
// in unsupported/Eigen/NonLinearOptimization). Shared by the logistic fit (evaluation.cpp) and
// the weight training (training.cpp); Eigen stays inside common/src.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <functional>

namespace qm3d::evaluation::detail {

/// r(x): #residuals values; J(x): #residuals by #parameters, J(i, k) = d r_i / d x_k.
struct LeastSquaresProblem {
  Eigen::Index residuals = 0;
  std::function<void(const Eigen::VectorXd& x, Eigen::VectorXd& r)> residual;
  std::function<void(const Eigen::VectorXd& x, Eigen::MatrixXd& jacobian)> jacobian;
  /// Optional: false for an accepted iterate outside the region where the model means
  /// something; the minimisation then stops there (LeastSquaresResult::left_region).
  std::function<bool(const Eigen::VectorXd& x)> admissible;
};

struct LeastSquaresResult {
  Eigen::VectorXd x;
  double sum_squares = 0;    ///< sum r_i^2 at x
  bool converged = false;    ///< MINPACK status 1..4 or 6..8 (tolerances met)
  bool left_region = false;  ///< stopped at the first iterate that was not admissible
  int evaluations = 0;
};

/// Minimises sum r_i(x)^2 from `start`. `tolerance` is MINPACK's ftol and xtol.
LeastSquaresResult minimize_least_squares(const LeastSquaresProblem& problem,
                                          const Eigen::VectorXd& start, int max_evaluations,
                                          double tolerance);

/// Largest |asymptote| of a fitted logistic, in standard deviations of the subjective scores
/// around their mean. When the data are nearly linear in the score, the least-squares logistic
/// runs off towards a straight line (asymptotes and scale growing without end, the residual
/// falling by ever smaller amounts); beyond this bound the curve is a straight line over the
/// data for every practical purpose, so the fit stops there instead of using up its evaluations.
inline constexpr double kMaxAsymptoteSd = 10.0;

/// Smallest scale |beta4| of a fitted logistic, in standard deviations of the scores. On data
/// with no trend the least-squares logistic becomes a step between two neighbouring scores and
/// sharpens without end. Its 10-90 % transition is 4.4 scales wide, so below this bound it spans
/// less than 5 % of a standard deviation - a handful of stimuli in a data set of hundreds, no
/// psychometric function - and the fit stops there (the curve is a step).
inline constexpr double kMinScaleSd = 1e-2;

/// True when both asymptotes (standardised units) are within kMaxAsymptoteSd and the scale
/// (standardised units) is at least kMinScaleSd.
inline bool logistic_admissible(double beta1, double beta2, double scale) {
  return std::abs(beta1) <= kMaxAsymptoteSd && std::abs(beta2) <= kMaxAsymptoteSd &&
         scale >= kMinScaleSd;
}

/// sigma(z) = 1 / (1 + exp(-z)), without overflow for large |z|.
double logistic_sigmoid(double z);

}  // namespace qm3d::evaluation::detail
