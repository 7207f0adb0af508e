#include "least_squares.h"

#include <cmath>
#include <unsupported/Eigen/NonLinearOptimization>

namespace qm3d::evaluation::detail {
namespace {

// The functor interface Eigen::LevenbergMarquardt expects (operator(), df, values, inputs).
struct Functor {
  const LeastSquaresProblem& problem;
  Eigen::Index parameter_count;

  Eigen::Index values() const { return problem.residuals; }
  Eigen::Index inputs() const { return parameter_count; }
  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& r) const {
    problem.residual(x, r);
    return r.allFinite() ? 0 : -1;  // negative: MINPACK stops ("UserAsked")
  }
  int df(const Eigen::VectorXd& x, Eigen::MatrixXd& jacobian) const {
    problem.jacobian(x, jacobian);
    return jacobian.allFinite() ? 0 : -1;
  }
};

bool is_converged(Eigen::LevenbergMarquardtSpace::Status status) {
  using namespace Eigen::LevenbergMarquardtSpace;
  switch (status) {
    case RelativeReductionTooSmall:
    case RelativeErrorTooSmall:
    case RelativeErrorAndReductionTooSmall:
    case CosinusTooSmall:
    case FtolTooSmall:
    case XtolTooSmall:
    case GtolTooSmall:
      return true;
    default:
      return false;
  }
}

}  // namespace

LeastSquaresResult minimize_least_squares(const LeastSquaresProblem& problem,
                                          const Eigen::VectorXd& start, int max_evaluations,
                                          double tolerance) {
  Functor functor{problem, start.size()};
  Eigen::LevenbergMarquardt<Functor> lm(functor);
  lm.parameters.maxfev = max_evaluations;
  lm.parameters.ftol = tolerance;
  lm.parameters.xtol = tolerance;
  LeastSquaresResult result;
  result.x = start;
  // Eigen's minimize(), one outer iteration at a time, to check each accepted iterate.
  auto status = lm.minimizeInit(result.x);
  while (status == Eigen::LevenbergMarquardtSpace::NotStarted ||
         status == Eigen::LevenbergMarquardtSpace::Running) {
    status = lm.minimizeOneStep(result.x);
    if (problem.admissible && !problem.admissible(result.x)) {
      result.left_region = true;
      break;
    }
  }
  Eigen::VectorXd r(problem.residuals);
  problem.residual(result.x, r);
  result.sum_squares = r.squaredNorm();
  result.converged = is_converged(status) && std::isfinite(result.sum_squares);
  result.evaluations = static_cast<int>(lm.nfev);
  return result;
}

double logistic_sigmoid(double z) {
  if (z >= 0) return 1.0 / (1.0 + std::exp(-z));
  const double e = std::exp(z);
  return e / (1.0 + e);
}

}  // namespace qm3d::evaluation::detail
