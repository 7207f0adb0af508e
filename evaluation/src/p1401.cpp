#include "qm3d/evaluation/p1401.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "least_squares.h"
#include "qm3d/common/error.h"
#include "qm3d/common/pooling.h"
#include "qm3d/common/statistics.h"

namespace qm3d::evaluation {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
/// Floor of the modified Lentz algorithm (Numerical Recipes §5.2): replaces a zero denominator.
constexpr double kLentzFloor = 1e-300;
/// Iterations allowed to the gamma series and the continued fractions. They need O(sqrt(a))
/// terms near the mean, so this covers shape parameters far beyond any subjective test.
constexpr int kMaxTerms = 100000;
/// The normal 97.5 % point as P.1401 writes it (§7.5.3: "K = 1.96").
constexpr double kP1401Z95 = 1.96;
/// Golden-section ratio (3 - sqrt 5) / 2, for the cubic's interior-contact search.
constexpr double kGolden = 0.3819660112501051;
/// Points of the scan of the cubic's interior double root t0 over [-1, 1].
constexpr int kDoubleRootScan = 2001;

// ---- distribution functions -------------------------------------------------------------------

void check_finite_positive(double v, const char* what, const char* function) {
  if (!(v > 0) || !std::isfinite(v)) {
    throw NumericError(std::string(function) + ": " + what + " must be positive and finite (got " +
                       std::to_string(v) + ")");
  }
}

// log of x^a e^-x / Gamma(a): the prefactor of both incomplete gamma expansions.
double log_gamma_prefactor(double a, double x) { return a * std::log(x) - x - std::lgamma(a); }

// P(a, x) = prefactor * sum_n x^n / (a (a+1) ... (a+n)), for x < a + 1.
double gamma_p_series(double a, double x) {
  if (x == 0) return 0;
  double term = 1 / a, sum = term;
  for (int n = 1; n < kMaxTerms; ++n) {
    term *= x / (a + n);
    sum += term;
    if (std::fabs(term) < std::fabs(sum) * kEpsilon) {
      return sum * std::exp(log_gamma_prefactor(a, x));
    }
  }
  throw NumericError("incomplete gamma: the series did not converge (a = " + std::to_string(a) +
                     ")");
}

// Q(a, x) = prefactor * 1/(x+1-a- 1(1-a)/(x+3-a- 2(2-a)/(x+5-a- ...))), for x >= a + 1,
// evaluated by the modified Lentz algorithm.
double gamma_q_fraction(double a, double x) {
  double b = x + 1 - a, c = 1 / kLentzFloor, d = 1 / b, h = d;
  for (int i = 1; i < kMaxTerms; ++i) {
    const double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::fabs(d) < kLentzFloor) d = kLentzFloor;
    c = b + an / c;
    if (std::fabs(c) < kLentzFloor) c = kLentzFloor;
    d = 1 / d;
    const double delta = d * c;
    h *= delta;
    if (std::fabs(delta - 1) < kEpsilon) return h * std::exp(log_gamma_prefactor(a, x));
  }
  throw NumericError(
      "incomplete gamma: the continued fraction did not converge (a = " + std::to_string(a) + ")");
}

void check_gamma_arguments(double a, double x) {
  check_finite_positive(a, "a", "incomplete gamma");
  if (!(x >= 0) || std::isnan(x)) {
    throw NumericError("incomplete gamma: x must be >= 0 (got " + std::to_string(x) + ")");
  }
}

// The continued fraction of I_x(a, b) (Numerical Recipes §6.4, eq. 6.4.5), modified Lentz;
// converges fast for x < (a + 1) / (a + b + 2).
double beta_fraction(double x, double a, double b) {
  const double qab = a + b, qap = a + 1, qam = a - 1;
  auto floor = [](double v) { return std::fabs(v) < kLentzFloor ? kLentzFloor : v; };
  double c = 1, d = 1 / floor(1 - qab * x / qap), h = d;
  for (int m = 1; m < kMaxTerms; ++m) {
    const double m2 = 2.0 * m;
    double aa = m * (b - m) * x / ((qam + m2) * (a + m2));  // even step d_{2m}
    d = 1 / floor(1 + aa * d);
    c = floor(1 + aa / c);
    h *= d * c;
    aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));  // odd step d_{2m+1}
    d = 1 / floor(1 + aa * d);
    c = floor(1 + aa / c);
    const double delta = d * c;
    h *= delta;
    if (std::fabs(delta - 1) < kEpsilon) return h;
  }
  throw NumericError("incomplete beta: the continued fraction did not converge (a = " +
                     std::to_string(a) + ", b = " + std::to_string(b) + ")");
}

// I_x(a, b) with y = 1 - x given separately, so that x near 1 keeps its digits in y.
double incomplete_beta(double x, double y, double a, double b) {
  if (x <= 0) return 0;
  if (y <= 0) return 1;
  const double log_front =
      std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log(y);
  if (x < (a + 1) / (a + b + 2)) return std::exp(log_front) * beta_fraction(x, a, b) / a;
  return 1 - std::exp(log_front) * beta_fraction(y, b, a) / b;
}

// h(u) = log T(a, e^u) - log target, made increasing in u; T = P (lower) or Q (upper). `slope`
// receives dh/du (NaN where T underflows).
double log_tail_gap(double a, double u, double log_target, bool upper, double& slope) {
  const double x = std::exp(u);
  const double tail = upper ? regularized_gamma_q(a, x) : regularized_gamma_p(a, x);
  const double x_density = std::exp(log_gamma_prefactor(a, x));  // x * d P / d x
  slope = tail > 0 ? x_density / tail : kNaN;
  const double gap = std::log(tail) - log_target;
  return upper ? -gap : gap;
}

// Solves T(a, x) = target for x by Newton's method on u = log x, kept inside a bracket of u
// (bisection where a Newton step would leave it).
double invert_gamma_tail(double a, double target, bool upper) {
  const double log_target = std::log(target);
  double slope = 0, lo = std::log(a), hi = lo;
  for (double step = 1; log_tail_gap(a, lo, log_target, upper, slope) > 0; step *= 2) lo -= step;
  for (double step = 1; log_tail_gap(a, hi, log_target, upper, slope) < 0; step *= 2) hi += step;
  double u = 0.5 * (lo + hi);
  for (int iteration = 0; iteration < 400 && hi - lo > 2 * kEpsilon * std::fabs(u); ++iteration) {
    const double gap = log_tail_gap(a, u, log_target, upper, slope);
    if (gap == 0) break;
    (gap < 0 ? lo : hi) = u;
    double next = u - gap / slope;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool settled = std::fabs(next - u) <= kEpsilon * std::max(1.0, std::fabs(u));
    u = next;
    if (settled) break;
  }
  return std::exp(u);
}

// ---- input checks -----------------------------------------------------------------------------

void check_same_length(std::size_t a, std::size_t b, const std::string& what) {
  if (a != b) {
    throw std::invalid_argument(what + ": lengths differ (" + std::to_string(a) + " vs " +
                                std::to_string(b) + ")");
  }
}

void check_finite_pairs(const std::vector<double>& x, const std::vector<double>& y,
                        const std::string& what) {
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) {
      throw NumericError(what + ": non-finite value at pair " + std::to_string(i + 1));
    }
  }
}

void check_more_than_d(std::size_t n, std::size_t d, const std::string& what) {
  if (n <= d) {
    throw NumericError(what + ": " + std::to_string(n) + " pairs for " + std::to_string(d) +
                       " mapping parameters; more pairs than parameters are needed (N - d "
                       "degrees of freedom, P.1401 §7.5.1)");
  }
}

// ---- closed-form mappings ---------------------------------------------------------------------

MappingFunction fit_linear(const std::vector<double>& x, const std::vector<double>& y) {
  const double mx = mean_pool(x), my = mean_pool(y);
  double sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    sxy += (x[i] - mx) * (y[i] - my);
  }
  if (!(sxx > 0)) throw NumericError("linear mapping: the scores are constant");
  const double slope = sxy / sxx;
  return {Mapping::linear, {slope, my - slope * mx}};
}

// A cubic c0 + c1 t + c2 t^2 + c3 t^3 in t in [-1, 1], with its sum of squared residuals.
using Cubic = std::array<double, 4>;
struct CubicCandidate {
  Cubic c{};
  double sum_squares = std::numeric_limits<double>::infinity();
};

double evaluate_cubic(const Cubic& c, double t) {
  return c[0] + t * (c[1] + t * (c[2] + t * c[3]));
}

double cubic_sum_squares(const Cubic& c, const std::vector<double>& t,
                         const std::vector<double>& y) {
  double sum = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    const double r = y[i] - evaluate_cubic(c, t[i]);
    sum += r * r;
  }
  return sum;
}

// True when f'(t) = c1 + 2 c2 t + 3 c3 t^2 keeps one sign on [-1, 1] (zeros allowed, to a
// rounding tolerance): checked at both ends and at the vertex of f' when it lies inside.
bool is_monotonic(const Cubic& c) {
  auto slope = [&](double t) { return c[1] + 2 * c[2] * t + 3 * c[3] * t * t; };
  std::vector<double> slopes = {slope(-1), slope(1)};
  if (c[3] != 0 && std::fabs(c[2] / (3 * c[3])) < 1) slopes.push_back(slope(-c[2] / (3 * c[3])));
  const double tolerance =
      1e-12 * (std::fabs(c[1]) + 2 * std::fabs(c[2]) + 3 * std::fabs(c[3])) + 1e-300;
  const auto [lo, hi] = std::minmax_element(slopes.begin(), slopes.end());
  return *lo >= -tolerance || *hi <= tolerance;
}

// Least squares over span(basis) (each basis function a cubic in t); column-pivoting QR, so a
// rank-deficient family still gets a (basic) solution. `rank` receives the design's rank.
CubicCandidate fit_cubic_family(const std::vector<double>& t, const std::vector<double>& y,
                                const std::vector<Cubic>& basis, Eigen::Index* rank = nullptr) {
  const auto n = static_cast<Eigen::Index>(t.size());
  const auto m = static_cast<Eigen::Index>(basis.size());
  Eigen::MatrixXd design(n, m);
  Eigen::VectorXd rhs(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < m; ++j) {
      design(i, j) =
          evaluate_cubic(basis[static_cast<std::size_t>(j)], t[static_cast<std::size_t>(i)]);
    }
    rhs[i] = y[static_cast<std::size_t>(i)];
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(design);
  if (rank) *rank = qr.rank();
  const Eigen::VectorXd w = qr.solve(rhs);
  CubicCandidate candidate;
  for (Eigen::Index j = 0; j < m; ++j) {
    for (std::size_t k = 0; k < 4; ++k)
      candidate.c[k] += w[j] * basis[static_cast<std::size_t>(j)][k];
  }
  candidate.sum_squares = cubic_sum_squares(candidate.c, t, y);
  return candidate;
}

// f = c0 + k (t - t0)^3 (f' = 3 k (t - t0)^2: monotonic for every k), least squares in (c0, k).
CubicCandidate fit_double_root(const std::vector<double>& t, const std::vector<double>& y,
                               double t0) {
  std::vector<double> g(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) g[i] = (t[i] - t0) * (t[i] - t0) * (t[i] - t0);
  const double mg = mean_pool(g), my = mean_pool(y);
  double sgg = 0, sgy = 0;
  for (std::size_t i = 0; i < g.size(); ++i) {
    sgg += (g[i] - mg) * (g[i] - mg);
    sgy += (g[i] - mg) * (y[i] - my);
  }
  const double k = sgg > 0 ? sgy / sgg : 0, c0 = my - k * mg;
  CubicCandidate candidate;
  candidate.c = {c0 - k * t0 * t0 * t0, 3 * k * t0 * t0, -3 * k * t0, k};
  candidate.sum_squares = cubic_sum_squares(candidate.c, t, y);
  return candidate;
}

// The best interior double root t0: a scan of [-1, 1], then golden-section search between the
// neighbours of the best scanned point.
CubicCandidate best_double_root(const std::vector<double>& t, const std::vector<double>& y) {
  auto t0_at = [](int i) { return -1 + 2.0 * i / (kDoubleRootScan - 1); };
  int best = 0;
  double best_sum = std::numeric_limits<double>::infinity();
  for (int i = 0; i < kDoubleRootScan; ++i) {
    const double s = fit_double_root(t, y, t0_at(i)).sum_squares;
    if (s < best_sum) {
      best_sum = s;
      best = i;
    }
  }
  auto profile = [&](double t0) { return fit_double_root(t, y, t0).sum_squares; };
  double a = t0_at(std::max(best - 1, 0)), b = t0_at(std::min(best + 1, kDoubleRootScan - 1));
  double p = a + kGolden * (b - a), q = b - kGolden * (b - a);
  double fp = profile(p), fq = profile(q);
  for (int iteration = 0; iteration < 200 && b - a > 1e-14; ++iteration) {
    if (fp <= fq) {  // the minimum is in [a, q]: q <- p, new p
      b = q;
      q = p;
      fq = fp;
      p = a + kGolden * (b - a);
      fp = profile(p);
    } else {  // the minimum is in [p, b]: p <- q, new q
      a = p;
      p = q;
      fp = fq;
      q = b - kGolden * (b - a);
      fq = profile(q);
    }
  }
  const CubicCandidate refined = fit_double_root(t, y, 0.5 * (a + b));
  return refined.sum_squares <= best_sum ? refined : fit_double_root(t, y, t0_at(best));
}

// The monotonic cubics on the boundary of the feasible cones (see fit_mapping): f'(-1) = 0,
// f'(1) = 0, both, or an interior double root; the monotonic one with the least residual.
CubicCandidate constrained_cubic(const std::vector<double>& t, const std::vector<double>& y) {
  const std::array<std::vector<Cubic>, 3> families = {{
      {{1, 0, 0, 0}, {0, 2, 1, 0}, {0, -3, 0, 1}},   // c1 = 2 c2 - 3 c3:  f'(-1) = 0
      {{1, 0, 0, 0}, {0, -2, 1, 0}, {0, -3, 0, 1}},  // c1 = -2 c2 - 3 c3: f'(+1) = 0
      {{1, 0, 0, 0}, {0, -3, 0, 1}},                 // f' = 3 c3 (t^2 - 1)
  }};
  CubicCandidate best = best_double_root(t, y);
  for (const std::vector<Cubic>& basis : families) {
    const CubicCandidate c = fit_cubic_family(t, y, basis);
    if (is_monotonic(c.c) && c.sum_squares < best.sum_squares) best = c;
  }
  return best;
}

// Coefficients in x of sum_k c_k ((x - mid) / half)^k.
std::vector<double> expand_cubic(const Cubic& c, double mid, double half) {
  std::vector<double> a(4, 0.0);
  const std::array<std::array<double, 4>, 4> binomial = {
      {{1, 0, 0, 0}, {1, 1, 0, 0}, {1, 2, 1, 0}, {1, 3, 3, 1}}};
  for (int k = 0; k < 4; ++k) {
    const double scale = c[static_cast<std::size_t>(k)] / std::pow(half, k);
    for (int j = 0; j <= k; ++j) {  // (x - mid)^k = sum_j C(k, j) x^j (-mid)^(k-j)
      a[static_cast<std::size_t>(j)] +=
          scale * binomial[static_cast<std::size_t>(k)][static_cast<std::size_t>(j)] *
          std::pow(-mid, k - j);
    }
  }
  return a;
}

MappingFit fit_cubic(const std::vector<double>& x, const std::vector<double>& y) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  const double mid = 0.5 * (*lo + *hi), half = 0.5 * (*hi - *lo);
  if (!(half > 0)) throw NumericError("cubic mapping: the scores are constant");
  std::vector<double> t;
  t.reserve(x.size());
  for (double v : x) t.push_back((v - mid) / half);
  Eigen::Index rank = 0;
  CubicCandidate fit =
      fit_cubic_family(t, y, {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}, &rank);
  if (rank < 4) throw NumericError("cubic mapping: fewer than 4 distinct scores");
  MappingFit result;
  result.constrained = !is_monotonic(fit.c);
  if (result.constrained) fit = constrained_cubic(t, y);
  result.function = {Mapping::cubic, expand_cubic(fit.c, mid, half)};
  for (double v : t) result.predicted.push_back(evaluate_cubic(fit.c, v));
  return result;
}

// ---- logistic mappings ------------------------------------------------------------------------

struct Standardised {
  std::vector<double> values;
  double mean = 0, sd = 0;
};

Standardised standardise(const std::vector<double>& v, const char* what) {
  Standardised s;
  s.mean = mean_pool(v);
  s.sd = population_sd(v, s.mean);
  if (!(s.sd > 0))
    throw NumericError(std::string("logistic5 mapping: the ") + what + " are constant");
  for (double x : v) s.values.push_back((x - s.mean) / s.sd);
  return s;
}

// b1 (sigma(b2 (u - b3)) - 1/2) + b4 u + b5, which is the VQEG FR-TV Phase I / LIVE form since
// 1/2 - 1/(1 + e^z) = sigma(z) - 1/2.
double logistic5(const double* b, double u) {
  return b[0] * (detail::logistic_sigmoid(b[1] * (u - b[2])) - 0.5) + b[3] * u + b[4];
}

detail::LeastSquaresProblem logistic5_problem(const std::vector<double>& u,
                                              const std::vector<double>& v) {
  detail::LeastSquaresProblem problem;
  problem.residuals = static_cast<Eigen::Index>(u.size());
  problem.residual = [&u, &v](const Eigen::VectorXd& b, Eigen::VectorXd& r) {
    for (std::size_t i = 0; i < u.size(); ++i) {
      r[static_cast<Eigen::Index>(i)] = logistic5(b.data(), u[i]) - v[i];
    }
  };
  problem.jacobian = [&u](const Eigen::VectorXd& b, Eigen::MatrixXd& jac) {
    for (std::size_t i = 0; i < u.size(); ++i) {
      const auto row = static_cast<Eigen::Index>(i);
      const double s = detail::logistic_sigmoid(b[1] * (u[i] - b[2]));
      const double slope = b[0] * s * (1 - s);  // d f / d z, z = b2 (u - b3)
      jac(row, 0) = s - 0.5;
      jac(row, 1) = slope * (u[i] - b[2]);
      jac(row, 2) = -slope * b[1];
      jac(row, 3) = u[i];
      jac(row, 4) = 1;
    }
  };
  // The logistic4 bounds (least_squares.h): a step of at most the span of two admissible
  // asymptotes, a scale of at least kMinScaleSd.
  problem.admissible = [](const Eigen::VectorXd& b) {
    return std::fabs(b[0]) <= 2 * detail::kMaxAsymptoteSd &&
           std::fabs(b[1]) <= 1 / detail::kMinScaleSd;
  };
  return problem;
}

// Standardised starts: the logistic4 optimum (b4 = 0) and logistic4's three starting scales.
std::vector<Eigen::VectorXd> logistic5_starts(const LogisticFunction& f4, const Standardised& x,
                                              const Standardised& y) {
  const double hi = (f4.beta1 - y.mean) / y.sd, lo = (f4.beta2 - y.mean) / y.sd;
  Eigen::VectorXd from4(5);
  from4 << hi - lo, x.sd / std::fabs(f4.beta4), (f4.beta3 - x.mean) / x.sd, 0, 0.5 * (hi + lo);
  std::vector<Eigen::VectorXd> starts = {from4};
  const auto [vmin, vmax] = std::minmax_element(y.values.begin(), y.values.end());
  const double step = (pearson(x.values, y.values) < 0 ? -1 : 1) * (*vmax - *vmin);
  for (double scale : {0.3, 1.0, 3.0}) {
    Eigen::VectorXd b(5);
    b << step, 1 / scale, 0, 0, 0.5 * (*vmax + *vmin);
    starts.push_back(b);
  }
  return starts;
}

// Raw-unit parameters of the standardised b, with b2 >= 0 ((b1, b2) and (-b1, -b2) are the
// same curve).
std::vector<double> logistic5_raw(const Eigen::VectorXd& b, const Standardised& x,
                                  const Standardised& y) {
  const double sign = b[1] < 0 ? -1 : 1;
  const double slope = y.sd * b[3] / x.sd;
  return {sign * y.sd * b[0], sign * b[1] / x.sd, x.mean + x.sd * b[2], slope,
          y.mean + y.sd * b[4] - slope * x.mean};
}

MappingFit fit_logistic5(const std::vector<double>& x, const std::vector<double>& y,
                         const LogisticFitOptions& options) {
  const LogisticFit f4 = fit_logistic(x, y, options);
  const Standardised sx = standardise(x, "scores"), sy = standardise(y, "subjective scores");
  const detail::LeastSquaresProblem problem = logistic5_problem(sx.values, sy.values);
  detail::LeastSquaresResult best;
  best.sum_squares = std::numeric_limits<double>::infinity();
  for (const Eigen::VectorXd& start : logistic5_starts(f4.function, sx, sy)) {
    detail::LeastSquaresResult r =
        detail::minimize_least_squares(problem, start, options.max_evaluations, options.tolerance);
    if (r.x.allFinite() && r.sum_squares < best.sum_squares) best = std::move(r);
  }
  if (!std::isfinite(best.sum_squares)) {
    throw NumericError("logistic5 mapping: no start reached a finite optimum");
  }
  MappingFit fit;
  fit.function = {Mapping::logistic5, logistic5_raw(best.x, sx, sy)};
  fit.converged = best.converged;
  fit.bounded = best.left_region;
  return fit;
}

MappingFit fit_logistic4(const std::vector<double>& x, const std::vector<double>& y,
                         const LogisticFitOptions& options) {
  const LogisticFit f4 = fit_logistic(x, y, options);
  MappingFit fit;
  const LogisticFunction& f = f4.function;
  fit.function = {Mapping::logistic4, {f.beta1, f.beta2, f.beta3, f.beta4}};
  fit.converged = f4.converged;
  fit.bounded = f4.bounded;
  return fit;
}

// ---- statistics -------------------------------------------------------------------------------

void check_statistics_input(const std::vector<double>& predicted, const std::vector<double>& mos,
                            std::size_t d, const std::vector<double>& ci95) {
  check_same_length(predicted.size(), mos.size(), "P.1401 statistics: predictions and MOS");
  if (!ci95.empty()) check_same_length(ci95.size(), mos.size(), "P.1401 statistics: MOS and CI");
  check_finite_pairs(predicted, mos, "P.1401 statistics");
  check_more_than_d(mos.size(), d, "P.1401 statistics");
  for (std::size_t i = 0; i < ci95.size(); ++i) {
    if (!(ci95[i] >= 0) || !std::isfinite(ci95[i])) {
      throw NumericError("P.1401 statistics: confidence interval " + std::to_string(i + 1) +
                         " is negative or not finite");
    }
  }
}

// sqrt(sum e_i^2 / dof) with its chi-square interval (P.1401 §7.5.1).
Statistic rmse_with_interval(double sum_squares, std::size_t dof) {
  const double k = static_cast<double>(dof);
  const double rmse = std::sqrt(sum_squares / k);
  return {rmse, Interval{rmse * std::sqrt(k / chi_square_quantile(0.975, k)),
                         rmse * std::sqrt(k / chi_square_quantile(0.025, k))}};
}

Statistic proportion_with_interval(double ratio, std::size_t n) {
  const double half = kP1401Z95 * std::sqrt(ratio * (1 - ratio) / static_cast<double>(n));
  return {ratio, Interval{std::max(0.0, ratio - half), std::min(1.0, ratio + half)}};
}

}  // namespace

// ---- public: mappings -------------------------------------------------------------------------

namespace {
constexpr std::array<std::pair<Mapping, std::string_view>, 5> kMappingNames = {{
    {Mapping::none, "none"},
    {Mapping::linear, "linear"},
    {Mapping::cubic, "cubic"},
    {Mapping::logistic4, "logistic4"},
    {Mapping::logistic5, "logistic5"},
}};
}  // namespace

std::string_view mapping_name(Mapping mapping) {
  for (const auto& [m, name] : kMappingNames) {
    if (m == mapping) return name;
  }
  throw std::invalid_argument("mapping_name: unknown mapping");
}

Mapping parse_mapping(std::string_view name) {
  for (const auto& [m, known] : kMappingNames) {
    if (known == name) return m;
  }
  throw std::invalid_argument("unknown mapping '" + std::string(name) +
                              "' (known: none, linear, cubic, logistic4, logistic5)");
}

std::size_t mapping_parameter_count(Mapping mapping) {
  switch (mapping) {
    case Mapping::none:
      return 0;
    case Mapping::linear:
      return 2;
    case Mapping::cubic:
    case Mapping::logistic4:
      return 4;
    case Mapping::logistic5:
      return 5;
  }
  throw std::invalid_argument("mapping_parameter_count: unknown mapping");
}

double MappingFunction::operator()(double x) const {
  const std::vector<double>& p = parameters;
  switch (mapping) {
    case Mapping::none:
      return x;
    case Mapping::linear:
      return p.at(0) * x + p.at(1);
    case Mapping::cubic:
      return p.at(0) + x * (p.at(1) + x * (p.at(2) + x * p.at(3)));
    case Mapping::logistic4:
      return LogisticFunction{p.at(0), p.at(1), p.at(2), p.at(3)}(x);
    case Mapping::logistic5:
      return p.at(0) * (detail::logistic_sigmoid(p.at(1) * (x - p.at(2))) - 0.5) + p.at(3) * x +
             p.at(4);
  }
  return kNaN;
}

MappingFit fit_mapping(const std::vector<double>& x, const std::vector<double>& y, Mapping mapping,
                       const LogisticFitOptions& options) {
  const std::string what = std::string(mapping_name(mapping)) + " mapping";
  check_same_length(x.size(), y.size(), what);
  check_finite_pairs(x, y, what);
  const std::size_t d = mapping_parameter_count(mapping);
  check_more_than_d(x.size(), d, what);
  MappingFit fit;
  switch (mapping) {
    case Mapping::none:
      fit.function = {Mapping::none, {}};
      break;
    case Mapping::linear:
      fit.function = fit_linear(x, y);
      break;
    case Mapping::cubic:
      fit = fit_cubic(x, y);
      break;
    case Mapping::logistic4:
      fit = fit_logistic4(x, y, options);
      break;
    case Mapping::logistic5:
      fit = fit_logistic5(x, y, options);
      break;
  }
  fit.parameter_count = d;
  if (fit.predicted.empty()) {
    for (double v : x) fit.predicted.push_back(fit.function(v));
  }
  return fit;
}

// ---- public: statistics -----------------------------------------------------------------------

P1401Statistics p1401_statistics(const std::vector<double>& predicted,
                                 const std::vector<double>& mos, std::size_t parameter_count,
                                 const std::vector<double>& mos_ci95) {
  check_statistics_input(predicted, mos, parameter_count, mos_ci95);
  P1401Statistics s;
  s.count = mos.size();
  s.parameter_count = parameter_count;
  s.degrees_of_freedom = s.count - parameter_count;
  s.plcc.value = pearson(predicted, mos);
  s.plcc.ci = correlation_interval(s.plcc.value, s.count);
  double sum_squares = 0, sum_squares_star = 0;
  for (std::size_t i = 0; i < mos.size(); ++i) {
    const double error = std::fabs(mos[i] - predicted[i]);
    sum_squares += error * error;
    if (!mos_ci95.empty()) {
      const double beyond = std::max(0.0, error - mos_ci95[i]);  // §7.7 Perror
      sum_squares_star += beyond * beyond;
    }
  }
  s.rmse = rmse_with_interval(sum_squares, s.degrees_of_freedom);
  if (!mos_ci95.empty()) {
    s.rmse_star = rmse_with_interval(sum_squares_star, s.degrees_of_freedom);
    const double ratio = outlier_ratio(predicted, mos, mos_ci95);
    s.outliers = static_cast<std::size_t>(std::lround(ratio * static_cast<double>(s.count)));
    s.outlier_ratio = proportion_with_interval(ratio, s.count);
  }
  return s;
}

std::optional<Interval> correlation_interval(double r, std::size_t n) {
  if (n <= 3 || !std::isfinite(r)) return std::nullopt;
  const double z = std::atanh(r);
  const double half = kP1401Z95 / std::sqrt(static_cast<double>(n - 3));
  return Interval{std::tanh(z - half), std::tanh(z + half)};
}

P1401Evaluation evaluate_p1401(const std::vector<double>& scores, const std::vector<double>& mos,
                               Mapping mapping, const std::vector<double>& mos_ci95,
                               const LogisticFitOptions& options) {
  P1401Evaluation e;
  e.fit = fit_mapping(scores, mos, mapping, options);
  e.statistics = p1401_statistics(e.fit.predicted, mos, e.fit.parameter_count, mos_ci95);
  return e;
}

double mos_ci95(double sd, std::size_t votes) {
  if (votes < 2) {
    throw NumericError("MOS confidence interval: " + std::to_string(votes) +
                       " votes, at least 2 needed");
  }
  if (!(sd >= 0) || !std::isfinite(sd)) {
    throw NumericError("MOS confidence interval: standard deviation " + std::to_string(sd) +
                       " is negative or not finite");
  }
  const double m = static_cast<double>(votes);
  return student_t_quantile(0.975, m - 1) * sd / std::sqrt(m);
}

// ---- public: significance tests ---------------------------------------------------------------

SignificanceTest compare_correlations(double r1, std::size_t n1, double r2, std::size_t n2) {
  for (double r : {r1, r2}) {
    if (!(r >= -1 && r <= 1)) {
      throw NumericError("Fisher z test: correlation " + std::to_string(r) + " is not in [-1, 1]");
    }
  }
  if (n1 <= 3 || n2 <= 3) {
    throw NumericError("Fisher z test: more than 3 stimuli needed (got " + std::to_string(n1) +
                       " and " + std::to_string(n2) + ")");
  }
  constexpr double kMaxR = 1 - 1e-15;
  const double z1 = std::atanh(std::clamp(r1, -kMaxR, kMaxR));
  const double z2 = std::atanh(std::clamp(r2, -kMaxR, kMaxR));
  const double sigma =
      std::sqrt(1.0 / static_cast<double>(n1 - 3) + 1.0 / static_cast<double>(n2 - 3));
  const double z = (z1 - z2) / sigma;
  return {z, two_sided_normal_p(z)};
}

SignificanceTest compare_rmse(double rmse1, std::size_t dof1, double rmse2, std::size_t dof2) {
  for (double r : {rmse1, rmse2}) {
    if (!(r >= 0) || !std::isfinite(r)) {
      throw NumericError("F test: rmse " + std::to_string(r) + " is negative or not finite");
    }
  }
  if (dof1 == 0 || dof2 == 0) throw NumericError("F test: 0 degrees of freedom");
  const bool first_larger = rmse1 >= rmse2;
  const double larger = first_larger ? rmse1 : rmse2, smaller = first_larger ? rmse2 : rmse1;
  if (larger == 0) return {1, 1};
  const double f = (larger / smaller) * (larger / smaller);
  const auto dof_larger = static_cast<double>(first_larger ? dof1 : dof2);
  const auto dof_smaller = static_cast<double>(first_larger ? dof2 : dof1);
  return {f, std::isinf(f) ? 0.0 : f_sf(f, dof_larger, dof_smaller)};
}

SignificanceTest compare_outlier_ratios(double or1, std::size_t n1, double or2, std::size_t n2) {
  for (double r : {or1, or2}) {
    if (!(r >= 0 && r <= 1)) {
      throw NumericError("outlier ratio test: ratio " + std::to_string(r) + " is not in [0, 1]");
    }
  }
  if (n1 == 0 || n2 == 0) throw NumericError("outlier ratio test: no stimuli");
  const double a = static_cast<double>(n1), b = static_cast<double>(n2);
  const double pooled = (a * or1 + b * or2) / (a + b);
  if (!(pooled > 0 && pooled < 1)) return {0, 1};
  const double z = (or1 - or2) / std::sqrt(pooled * (1 - pooled) * (1 / a + 1 / b));
  return {z, two_sided_normal_p(z)};
}

P1401Comparison compare_p1401(const P1401Statistics& a, const P1401Statistics& b) {
  P1401Comparison c;
  c.plcc = compare_correlations(a.plcc.value, a.count, b.plcc.value, b.count);
  c.rmse = compare_rmse(a.rmse.value, a.degrees_of_freedom, b.rmse.value, b.degrees_of_freedom);
  if (a.rmse_star && b.rmse_star) {
    c.rmse_star = compare_rmse(a.rmse_star->value, a.degrees_of_freedom, b.rmse_star->value,
                               b.degrees_of_freedom);
  }
  if (a.outlier_ratio && b.outlier_ratio) {
    c.outlier_ratio =
        compare_outlier_ratios(a.outlier_ratio->value, a.count, b.outlier_ratio->value, b.count);
  }
  return c;
}

// ---- public: distribution functions -----------------------------------------------------------

double normal_sf(double z) { return 0.5 * std::erfc(z / std::sqrt(2.0)); }

double two_sided_normal_p(double z) { return std::erfc(std::fabs(z) / std::sqrt(2.0)); }

double regularized_gamma_p(double a, double x) {
  check_gamma_arguments(a, x);
  if (std::isinf(x)) return 1;
  return x < a + 1 ? gamma_p_series(a, x) : 1 - gamma_q_fraction(a, x);
}

double regularized_gamma_q(double a, double x) {
  check_gamma_arguments(a, x);
  if (std::isinf(x)) return 0;
  return x < a + 1 ? 1 - gamma_p_series(a, x) : gamma_q_fraction(a, x);
}

double chi_square_quantile(double p, double dof) {
  check_finite_positive(dof, "degrees of freedom", "chi-square quantile");
  if (!(p > 0 && p < 1)) {
    throw NumericError("chi-square quantile: p must be in (0, 1) (got " + std::to_string(p) + ")");
  }
  const bool upper = p > 0.5;
  return 2 * invert_gamma_tail(0.5 * dof, upper ? 1 - p : p, upper);
}

double regularized_beta(double x, double a, double b) {
  check_finite_positive(a, "a", "incomplete beta");
  check_finite_positive(b, "b", "incomplete beta");
  if (!(x >= 0 && x <= 1)) {
    throw NumericError("incomplete beta: x must be in [0, 1] (got " + std::to_string(x) + ")");
  }
  return incomplete_beta(x, 1 - x, a, b);
}

double f_sf(double f, double d1, double d2) {
  check_finite_positive(d1, "numerator degrees of freedom", "F distribution");
  check_finite_positive(d2, "denominator degrees of freedom", "F distribution");
  if (std::isnan(f)) throw NumericError("F distribution: F is NaN");
  if (f <= 0) return 1;
  if (std::isinf(f)) return 0;
  const double denominator = d2 + d1 * f;
  return incomplete_beta(d2 / denominator, d1 * f / denominator, 0.5 * d2, 0.5 * d1);
}

double student_t_sf(double t, double dof) {
  check_finite_positive(dof, "degrees of freedom", "Student t");
  if (std::isnan(t)) throw NumericError("Student t: t is NaN");
  if (t < 0) return 1 - student_t_sf(-t, dof);
  if (std::isinf(t)) return 0;
  const double denominator = dof + t * t;
  return 0.5 * incomplete_beta(dof / denominator, t * t / denominator, 0.5 * dof, 0.5);
}

double student_t_quantile(double p, double dof) {
  check_finite_positive(dof, "degrees of freedom", "Student t quantile");
  if (!(p > 0 && p < 1)) {
    throw NumericError("Student t quantile: p must be in (0, 1) (got " + std::to_string(p) + ")");
  }
  if (p == 0.5) return 0;
  const double tail = p < 0.5 ? p : 1 - p;  // solve P(T > t) = tail for t > 0
  double lo = 0, hi = 1;
  while (student_t_sf(hi, dof) > tail) lo = hi, hi *= 2;
  for (int iteration = 0; iteration < 200 && hi - lo > 2 * kEpsilon * hi; ++iteration) {
    const double mid = 0.5 * (lo + hi);
    (student_t_sf(mid, dof) > tail ? lo : hi) = mid;
  }
  return (p < 0.5 ? -0.5 : 0.5) * (lo + hi);
}

}  // namespace qm3d::evaluation
