#include "qm3d/evaluation/p1401.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "qm3d/common/error.h"

// Reference values marked "scipy" were computed with SciPy 1.10.1 / NumPy 1.24.2 (Debian 12
// python3-scipy), e.g. python3 -c 'import scipy.stats as s; print(repr(s.chi2.ppf(0.025, 8)))',
// and pasted here as literals.

namespace qm3d {
namespace {
using namespace qm3d::evaluation;  // the toolkit under test (qm3d/evaluation/)

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void expect_relative(double actual, double expected, double tolerance) {
  EXPECT_NEAR(actual, expected, tolerance * std::fabs(expected)) << "expected " << expected;
}

double sum_squares(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
  return s;
}

// ---- distribution functions -------------------------------------------------------------------

TEST(P1401Distributions, NormalSfMatchesScipy) {
  const double cases[][2] = {
      // {z, scipy.stats.norm.sf(z)}
      {0.0, 0.5},
      {1.0, 0.15865525393145707},
      {1.96, 0.024997895148220435},
      {-1.96, 0.9750021048517795},
      {5.0, 2.866515718791933e-07},
      {10.0, 7.61985302416047e-24},
      {20.0, 2.7536241186061556e-89},
      {37.0, 5.7255712225239266e-300},
      {-8.0, 0.9999999999999993},
  };
  // sf(z) has condition number z^2 in z: at z = 37 the rounding of z / sqrt 2 alone moves it by
  // ~1.5e-13 relative.
  for (const auto& c : cases) expect_relative(normal_sf(c[0]), c[1], 1e-12);
}

TEST(P1401Distributions, ChiSquareQuantileMatchesScipy) {
  const double cases[][3] = {
      // {p, dof, scipy.stats.chi2.ppf(p, dof)}
      {0.025, 1.0, 0.0009820691171752555},
      {0.975, 1.0, 5.023886187314888},
      {0.025, 2.0, 0.05063561596857975},
      {0.975, 2.0, 7.377758908227871},
      {0.025, 6.0, 1.2373442457912027},
      {0.975, 6.0, 14.44937533544792},
      {0.025, 8.0, 2.1797307472526497},
      {0.975, 8.0, 17.534546139484647},
      {0.025, 30.0, 16.79077226556663},
      {0.975, 30.0, 46.97924224367115},
      {0.025, 1000.0, 914.257153799259},
      {0.975, 1000.0, 1089.5309127749135},
      {1e-10, 1.0, 1.570796326794896e-20},  // extreme lower tail
      {1e-300, 3.0, 2.4179879310247908e-200},
      {0.999999999999, 4.0, 62.19979205810759},  // extreme upper tail
      {0.5, 0.5, 0.0873476047057468},
      {1e-05, 2.5, 0.000221022355866783},
      {0.999999, 200.0, 309.83809198992293},
      {0.3, 7.0, 4.671330448981073},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(testing::Message() << "p " << c[0] << " dof " << c[1]);
    expect_relative(chi_square_quantile(c[0], c[1]), c[2], 1e-12);
  }
}

TEST(P1401Distributions, ChiSquareQuantileInvertsTheCdf) {
  for (double dof : {0.3, 1.0, 4.0, 17.0, 250.0}) {
    for (double p : {1e-8, 0.01, 0.2, 0.5, 0.8, 0.99}) {
      const double x = chi_square_quantile(p, dof);
      expect_relative(regularized_gamma_p(0.5 * dof, 0.5 * x), p, 1e-12);
    }
  }
}

TEST(P1401Distributions, IncompleteGammaMatchesScipy) {
  const double cases[][4] = {
      // {a, x, scipy.special.gammainc(a, x), gammaincc(a, x)}
      {0.5, 0.1, 0.34527915398142317, 0.6547208460185768},
      {3.0, 2.5, 0.45618688411667035, 0.5438131158833297},
      {10.0, 15.0, 0.9301463393005901, 0.06985366069940986},
      {100.0, 90.0, 0.15822098918643007, 0.84177901081357},
      {2.5, 30.0, 0.9999999999878454, 1.2154569777183007e-11},
      {0.01, 1e-05, 0.8963367982671969, 0.10366320173280281},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(testing::Message() << "a " << c[0] << " x " << c[1]);
    expect_relative(regularized_gamma_p(c[0], c[1]), c[2], 1e-13);
    expect_relative(regularized_gamma_q(c[0], c[1]), c[3], 1e-12);
  }
  EXPECT_EQ(regularized_gamma_p(2, 0), 0);
  EXPECT_EQ(regularized_gamma_q(2, 0), 1);
}

TEST(P1401Distributions, IncompleteBetaMatchesScipy) {
  const double cases[][4] = {
      // {x, a, b, scipy.special.betainc(a, b, x)}
      {0.3, 2.0, 5.0, 0.5798250000000001},      {0.9, 0.5, 0.5, 0.7951672353008662},
      {0.01, 10.0, 3.0, 6.480550000000002e-19}, {0.999, 50.0, 2.0, 0.9987659096068829},
      {1e-08, 1.5, 4.0, 6.562499881875e-12},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(testing::Message() << "x " << c[0] << " a " << c[1] << " b " << c[2]);
    expect_relative(regularized_beta(c[0], c[1], c[2]), c[3], 1e-12);
  }
  // By symmetry I_{1/2}(a, a) = 1/2 (scipy gives 0.499999999999908 for a = 200).
  EXPECT_NEAR(regularized_beta(0.5, 200, 200), 0.5, 1e-12);
  // I_x(1, 1) = x; I_x(a, 1) = x^a.
  EXPECT_NEAR(regularized_beta(0.37, 1, 1), 0.37, 1e-15);
  EXPECT_NEAR(regularized_beta(0.6, 3, 1), 0.216, 1e-15);
}

TEST(P1401Distributions, FSfMatchesScipy) {
  const double cases[][4] = {
      // {f, d1, d2, scipy.stats.f.sf(f, d1, d2)}
      {1.0, 5.0, 5.0, 0.5000000000000001},
      {2.5, 8.0, 6.0, 0.14021872421303597},
      {10.0, 3.0, 100.0, 8.001257542330615e-06},
      {100.0, 50.0, 50.0, 3.917696515209776e-37},  // extreme tail
      {1.0001, 1000.0, 1000.0, 0.4993694063372028},
      {0.1, 2.0, 3.0, 0.9077304717673633},
      {3.0, 1.0, 1.0, 0.33333333333333337},
      {1000000.0, 4.0, 4.0, 2.9999920000150003e-12},
      {50.0, 20.0, 30.0, 9.387262400342458e-18},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(testing::Message() << "F " << c[0] << " d1 " << c[1] << " d2 " << c[2]);
    expect_relative(f_sf(c[0], c[1], c[2]), c[3], 1e-11);
  }
  EXPECT_EQ(f_sf(0, 3, 4), 1);
}

TEST(P1401Distributions, StudentTMatchesScipy) {
  // scipy's t.ppf (cdflib) is itself off by up to 4e-10 relative here (t.ppf(0.975, 1) =
  // 12.706204736432095 against tan(0.475 pi) = 12.706204736174698), so the references are the
  // closed forms for 1 and 2 dof and, above, the root of 0.5 betainc(dof/2, 1/2, dof/(dof+t^2))
  // = 0.025 found by scipy.optimize.brentq(xtol=1e-15, rtol=1e-15).
  expect_relative(student_t_quantile(0.975, 1), std::tan(0.475 * std::acos(-1.0)), 1e-14);
  expect_relative(student_t_quantile(0.975, 2), 0.95 / std::sqrt(2 * 0.975 * 0.025), 1e-14);
  const double quantiles[][2] = {
      // {dof, t with P(T > t) = 0.025}
      {5.0, 2.5705818356363155},
      {14.0, 2.1447866879178035},
      {29.0, 2.0452296421327043},
      {100.0, 1.9839715185235531},
  };
  for (const auto& c : quantiles) {
    expect_relative(student_t_quantile(0.975, c[0]), c[1], 1e-13);
    expect_relative(student_t_quantile(0.025, c[0]), -c[1], 1e-13);
  }
  const double tails[][3] = {
      // {t, dof, scipy.stats.t.sf(t, dof)}
      {2.0, 3.0, 0.06966298427942155},
      {-1.0, 10.0, 0.82955343384897},
      {40.0, 5.0, 9.205981085886476e-08},
  };
  for (const auto& c : tails) expect_relative(student_t_sf(c[0], c[1]), c[2], 1e-12);
}

TEST(P1401Distributions, BadArgumentsThrow) {
  EXPECT_THROW(chi_square_quantile(0, 3), NumericError);
  EXPECT_THROW(chi_square_quantile(1, 3), NumericError);
  EXPECT_THROW(chi_square_quantile(0.5, 0), NumericError);
  EXPECT_THROW(chi_square_quantile(kNaN, 3), NumericError);
  EXPECT_THROW(regularized_gamma_p(-1, 2), NumericError);
  EXPECT_THROW(regularized_gamma_q(1, -2), NumericError);
  EXPECT_THROW(regularized_beta(1.5, 1, 1), NumericError);
  EXPECT_THROW(regularized_beta(0.5, 0, 1), NumericError);
  EXPECT_THROW(f_sf(2, 0, 3), NumericError);
  EXPECT_THROW(f_sf(kNaN, 2, 3), NumericError);
  EXPECT_THROW(student_t_quantile(0.975, 0), NumericError);
}

// ---- mappings ---------------------------------------------------------------------------------

TEST(P1401Mapping, NamesRoundTrip) {
  for (Mapping m :
       {Mapping::none, Mapping::linear, Mapping::cubic, Mapping::logistic4, Mapping::logistic5}) {
    EXPECT_EQ(parse_mapping(mapping_name(m)), m);
  }
  EXPECT_EQ(mapping_name(Mapping::logistic5), "logistic5");
  try {
    parse_mapping("quadratic");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'quadratic'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("logistic4"), std::string::npos) << e.what();
  }
}

TEST(P1401Mapping, ParameterCounts) {
  EXPECT_EQ(mapping_parameter_count(Mapping::none), 0u);
  EXPECT_EQ(mapping_parameter_count(Mapping::linear), 2u);
  EXPECT_EQ(mapping_parameter_count(Mapping::cubic), 4u);
  EXPECT_EQ(mapping_parameter_count(Mapping::logistic4), 4u);
  EXPECT_EQ(mapping_parameter_count(Mapping::logistic5), 5u);
}

TEST(P1401Mapping, NoneIsTheIdentity) {
  const std::vector<double> x = {0.5, 2, 1}, y = {1, 2, 3};
  const MappingFit fit = fit_mapping(x, y, Mapping::none);
  EXPECT_EQ(fit.predicted, x);
  EXPECT_EQ(fit.parameter_count, 0u);
  EXPECT_EQ(fit.function(7.25), 7.25);
}

TEST(P1401Mapping, LinearIsExactOnLinearData) {
  const std::vector<double> x = {-3, 0.5, 1, 4, 9.5};
  std::vector<double> y;
  for (double v : x) y.push_back(2.5 * v - 1);
  const MappingFit fit = fit_mapping(x, y, Mapping::linear);
  ASSERT_EQ(fit.function.parameters.size(), 2u);
  EXPECT_NEAR(fit.function.parameters[0], 2.5, 1e-14);
  EXPECT_NEAR(fit.function.parameters[1], -1, 1e-14);
  for (std::size_t i = 0; i < x.size(); ++i) EXPECT_NEAR(fit.predicted[i], y[i], 1e-13);
  EXPECT_EQ(fit.parameter_count, 2u);
}

TEST(P1401Mapping, CubicOnMonotonicDataIsNumpyPolyfit) {
  const std::vector<double> x = {0, 0.5, 1.3, 2, 2.8, 3.5, 4.1, 5, 5.5, 6.3};
  const std::vector<double> y = {1.0, 1.5, 2.1, 2.4, 3.0, 3.2, 3.5, 3.7, 3.9, 4.0};
  // numpy.polyfit(x, y, 3)[::-1]; its derivative stays >= 0.1655 over [0, 6.3].
  const std::vector<double> expected = {1.0320271569000843, 0.8921370967388552,
                                        -0.08420150505716548, 0.002807854502854723};
  const MappingFit fit = fit_mapping(x, y, Mapping::cubic);
  EXPECT_FALSE(fit.constrained);
  ASSERT_EQ(fit.function.parameters.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k)
    expect_relative(fit.function.parameters[k], expected[k], 1e-10);
  for (std::size_t i = 0; i < x.size(); ++i)
    EXPECT_NEAR(fit.predicted[i], fit.function(x[i]), 1e-12);
}

TEST(P1401Mapping, CubicRecoversAnExactMonotonicCubic) {
  std::vector<double> x, y;
  for (int i = 0; i < 12; ++i) {
    x.push_back(10 + 0.5 * i);
    y.push_back(1 + 0.2 * x.back() - 0.01 * x.back() * x.back() + 0.001 * std::pow(x.back(), 3));
  }
  const MappingFit fit = fit_mapping(x, y, Mapping::cubic);
  EXPECT_FALSE(fit.constrained);
  for (std::size_t i = 0; i < x.size(); ++i) EXPECT_NEAR(fit.predicted[i], y[i], 1e-12);
}

// Rises then falls: the least-squares cubic is not monotonic (numpy: its derivative spans
// [-0.489, 1.372] over [0, 9]).
const std::vector<double> kHumpX = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9};
const std::vector<double> kHumpY = {1, 2, 3, 3.6, 4, 4.1, 4.0, 3.7, 3.3, 3.0};

void expect_monotonic_over(const MappingFunction& f, double lo, double hi, bool increasing) {
  double previous = f(lo);
  for (int i = 1; i <= 4000; ++i) {
    const double v = f(lo + (hi - lo) * i / 4000.0);
    EXPECT_TRUE(increasing ? v >= previous - 1e-12 : v <= previous + 1e-12) << "at step " << i;
    previous = v;
  }
}

TEST(P1401Mapping, NonMonotonicCubicIsConstrained) {
  const MappingFit fit = fit_mapping(kHumpX, kHumpY, Mapping::cubic);
  EXPECT_TRUE(fit.constrained);
  expect_monotonic_over(fit.function, 0, 9, /*increasing=*/true);
  // The optimum touches f' = 0 inside (x0 ~ 6.836): numpy least squares of c0 + k (x - x0)^3,
  // minimised over x0 by scipy.optimize.minimize_scalar(xatol=1e-12): sum of squares
  // 1.4879337730482023 at x0 = 6.835784800121229, i.e. the coefficients below. Independent
  // check: scipy.optimize.minimize (SLSQP, ftol 1e-16) of the sum of squares under f'(x) >= 0
  // at 40001 points of [0, 9] (a relaxation: it can only be lower) gives 1.487933770270114.
  // The decreasing optimum is the constant (8.861).
  const double ss = sum_squares(fit.predicted, kHumpY);
  EXPECT_NEAR(ss, 1.4879337730482023, 1e-12);
  EXPECT_GE(ss, 1.487933770270114);
  const std::vector<double> expected = {1.117411395508205, 1.1561954740723437, -0.1691386589659521,
                                        0.00824770741578214};
  for (std::size_t k = 0; k < 4; ++k)
    expect_relative(fit.function.parameters[k], expected[k], 1e-7);
}

TEST(P1401Mapping, ConstrainedCubicIsMirrorSymmetric) {
  std::vector<double> negated;
  for (double v : kHumpY) negated.push_back(-v);
  const MappingFit up = fit_mapping(kHumpX, kHumpY, Mapping::cubic);
  const MappingFit down = fit_mapping(kHumpX, negated, Mapping::cubic);
  EXPECT_TRUE(down.constrained);
  expect_monotonic_over(down.function, 0, 9, /*increasing=*/false);
  for (std::size_t i = 0; i < kHumpX.size(); ++i)
    EXPECT_NEAR(down.predicted[i], -up.predicted[i], 1e-10);
}

TEST(P1401Mapping, ConstrainedCubicAtAnEndpoint) {
  // Falls a little at the start, then rises steadily: the optimum has f' = 0 at the left end
  // (or a double root there); it must be monotonic and no worse than the best line.
  const std::vector<double> x = {0, 1, 2, 3, 4, 5, 6, 7};
  const std::vector<double> y = {2.0, 1.5, 1.6, 2.0, 2.6, 3.3, 4.1, 5.0};
  const MappingFit fit = fit_mapping(x, y, Mapping::cubic);
  EXPECT_TRUE(fit.constrained);
  expect_monotonic_over(fit.function, 0, 7, /*increasing=*/true);
  // numpy least squares with f'(0) = 0 (columns 1, x^2, x^3): 0.261900049021198 at
  // (1.6235655892816583, 0, 0.04330112712710538, 0.0038894355713673112), monotonic; scipy SLSQP
  // under f'(x) >= 0 at 40001 points of [0, 7] finds the same point (0.26190004945, f'(0) = 5e-17).
  EXPECT_NEAR(sum_squares(fit.predicted, y), 0.261900049021198, 1e-13);
  const std::vector<double> expected = {1.6235655892816583, 0, 0.04330112712710538,
                                        0.0038894355713673112};
  for (std::size_t k = 0; k < 4; ++k) EXPECT_NEAR(fit.function.parameters[k], expected[k], 1e-12);
  const MappingFit line = fit_mapping(x, y, Mapping::linear);
  EXPECT_LE(sum_squares(fit.predicted, y), sum_squares(line.predicted, y));
}

TEST(P1401Mapping, ConstrainedCubicPropertiesOnRandomData) {
  // Every monotonic line is a monotonic cubic, so the constrained optimum is never worse than the
  // least-squares line, and never better than the unconstrained cubic.
  std::mt19937_64 rng(7);
  auto uniform = [&rng] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  int constrained = 0;
  for (int trial = 0; trial < 40; ++trial) {
    std::vector<double> x, y;
    const double bend = 4 * uniform() - 2;
    for (int i = 0; i < 15; ++i) {
      x.push_back(10 * uniform());
      y.push_back(x.back() + bend * std::pow(x.back() - 5, 2) + 3 * uniform());
    }
    const MappingFit fit = fit_mapping(x, y, Mapping::cubic);
    const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
    const bool increasing = fit.function(*hi) >= fit.function(*lo);
    expect_monotonic_over(fit.function, *lo, *hi, increasing);
    const double ss = sum_squares(fit.predicted, y);
    EXPECT_LE(ss, sum_squares(fit_mapping(x, y, Mapping::linear).predicted, y) * (1 + 1e-12));
    constrained += fit.constrained;
  }
  EXPECT_GT(constrained, 10);  // the trials exercise the constrained path
  EXPECT_LT(constrained, 40);
}

TEST(P1401Mapping, Logistic5OnLinearDataStaysFinite) {
  std::vector<double> x, y;
  for (int i = 0; i < 30; ++i) {
    x.push_back(i);
    y.push_back(1 + 0.1 * i + 0.01 * ((i * 7) % 5 - 2));
  }
  const MappingFit fit = fit_mapping(x, y, Mapping::logistic5);
  for (double p : fit.function.parameters) EXPECT_TRUE(std::isfinite(p));
  EXPECT_LE(sum_squares(fit.predicted, y),
            sum_squares(fit_mapping(x, y, Mapping::logistic4).predicted, y) * (1 + 1e-9));
}

TEST(P1401Mapping, Logistic4IsFitLogistic) {
  const std::vector<double> x = {0.1, 0.4, 0.9, 1.3, 2.0, 2.2, 3.1, 3.5};
  const std::vector<double> y = {4.6, 4.5, 4.0, 3.1, 2.0, 1.9, 1.3, 1.2};
  const MappingFit fit = fit_mapping(x, y, Mapping::logistic4);
  const LogisticFit direct = fit_logistic(x, y);
  EXPECT_EQ(fit.function.parameters,
            (std::vector<double>{direct.function.beta1, direct.function.beta2,
                                 direct.function.beta3, direct.function.beta4}));
  for (std::size_t i = 0; i < x.size(); ++i) EXPECT_EQ(fit.predicted[i], direct.function(x[i]));
}

TEST(P1401Mapping, Logistic5RecoversNoiseFreeParameters) {
  const std::vector<double> truth = {2.0, 1.5, 3.0, 0.2, 2.5};
  const MappingFunction f{Mapping::logistic5, truth};
  std::vector<double> x, y;
  for (int i = 0; i < 25; ++i) {
    x.push_back(0.25 * i);
    y.push_back(f(x.back()));
  }
  // The formula, written out: b1 (1/2 - 1/(1 + exp(b2 (x - b3)))) + b4 x + b5.
  EXPECT_NEAR(f(1.0), 2.0 * (0.5 - 1 / (1 + std::exp(1.5 * (1.0 - 3.0)))) + 0.2 + 2.5, 1e-15);
  const MappingFit fit = fit_mapping(x, y, Mapping::logistic5);
  EXPECT_TRUE(fit.converged);
  ASSERT_EQ(fit.function.parameters.size(), 5u);
  for (std::size_t k = 0; k < 5; ++k) EXPECT_NEAR(fit.function.parameters[k], truth[k], 1e-6) << k;
  EXPECT_EQ(fit.parameter_count, 5u);
}

TEST(P1401Mapping, Logistic5IsNeverWorseThanLogistic4) {
  const std::vector<double> x = {0.1, 0.4, 0.9, 1.3, 2.0, 2.2, 3.1, 3.5, 4.0, 4.4};
  const std::vector<double> y = {4.6, 4.5, 4.0, 3.1, 2.3, 1.9, 1.5, 1.2, 1.1, 0.7};
  const MappingFit four = fit_mapping(x, y, Mapping::logistic4);
  const MappingFit five = fit_mapping(x, y, Mapping::logistic5);
  EXPECT_LE(sum_squares(five.predicted, y), sum_squares(four.predicted, y) * (1 + 1e-9));
  EXPECT_GE(five.function.parameters[1], 0);  // canonical sign of b2
}

TEST(P1401Mapping, BadInputThrows) {
  const std::vector<double> x4 = {1, 2, 3, 4}, y4 = {1, 3, 2, 4};
  EXPECT_THROW(fit_mapping(x4, y4, Mapping::cubic), NumericError);           // N = d
  EXPECT_THROW(fit_mapping({1, 2}, {1, 2}, Mapping::linear), NumericError);  // N = d
  EXPECT_NO_THROW(fit_mapping({1, 2, 3}, {1, 2, 2}, Mapping::linear));
  EXPECT_THROW(fit_mapping({1, 2, 3}, {1, 2}, Mapping::linear), std::invalid_argument);
  EXPECT_THROW(fit_mapping({1, kNaN, 3}, {1, 2, 3}, Mapping::linear), NumericError);
  EXPECT_THROW(fit_mapping({1, 1, 1}, {1, 2, 3}, Mapping::linear), NumericError);
  EXPECT_THROW(fit_mapping({1, 1, 2, 2, 3, 3}, {1, 2, 3, 4, 5, 6}, Mapping::cubic), NumericError);
  EXPECT_THROW(fit_mapping({1, 2, 3, 4, 5}, {1, 2, 3, 4, 5}, Mapping::logistic5), NumericError);
  try {
    fit_mapping(x4, y4, Mapping::cubic);
  } catch (const NumericError& e) {
    EXPECT_NE(std::string(e.what()).find("cubic mapping: 4 pairs for 4"), std::string::npos)
        << e.what();
  }
}

// ---- statistics of one model ------------------------------------------------------------------

// A fixed data set: 10 stimuli, linear mapping (d = 2, 8 degrees of freedom).
const std::vector<double> kScores = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
const std::vector<double> kMos = {1.2, 1.9, 2.4, 3.1, 3.3, 3.9, 4.1, 4.3, 4.6, 4.7};
const std::vector<double> kCi95 = {0.3, 0.2, 0.25, 0.1, 0.4, 0.2, 0.15, 0.3, 0.2, 0.35};

TEST(P1401Statistics, ValuesFromTheFormulas) {
  const MappingFit fit = fit_mapping(kScores, kMos, Mapping::linear);
  const P1401Statistics s = p1401_statistics(fit.predicted, kMos, fit.parameter_count, kCi95);
  EXPECT_EQ(s.count, 10u);
  EXPECT_EQ(s.degrees_of_freedom, 8u);

  // Independent recomputation, straight from P.1401 §7.5.1, §7.5.2.2, §7.5.3, §7.7.
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < 10; ++i) mx += kScores[i] / 10, my += kMos[i] / 10;
  double sxx = 0, sxy = 0, syy = 0;
  for (std::size_t i = 0; i < 10; ++i) {
    sxx += (kScores[i] - mx) * (kScores[i] - mx);
    sxy += (kScores[i] - mx) * (kMos[i] - my);
    syy += (kMos[i] - my) * (kMos[i] - my);
  }
  const double a = sxy / sxx, b = my - a * mx;
  double ss = 0, ss_star = 0;
  int outliers = 0;
  for (std::size_t i = 0; i < 10; ++i) {
    const double e = std::fabs(kMos[i] - (a * kScores[i] + b));
    ss += e * e;
    ss_star += std::pow(std::max(0.0, e - kCi95[i]), 2);
    outliers += e > kCi95[i];
  }
  const double rmse = std::sqrt(ss / 8), rmse_star = std::sqrt(ss_star / 8);
  const double chi2_975 = 17.534546139484647, chi2_025 = 2.1797307472526497;  // scipy, 8 dof
  EXPECT_NEAR(s.rmse.value, rmse, 1e-14);
  EXPECT_NEAR(s.rmse.ci->low, rmse * std::sqrt(8 / chi2_975), 1e-13);
  EXPECT_NEAR(s.rmse.ci->high, rmse * std::sqrt(8 / chi2_025), 1e-13);
  ASSERT_TRUE(s.rmse_star.has_value());
  EXPECT_NEAR(s.rmse_star->value, rmse_star, 1e-14);
  EXPECT_NEAR(s.rmse_star->ci->low, rmse_star * std::sqrt(8 / chi2_975), 1e-13);
  EXPECT_NEAR(s.rmse_star->ci->high, rmse_star * std::sqrt(8 / chi2_025), 1e-13);

  // Linear mapping: Pearson(MOSp, MOS) = Pearson(x, MOS).
  const double r = sxy / std::sqrt(sxx * syy);
  EXPECT_NEAR(s.plcc.value, r, 1e-14);
  EXPECT_NEAR(s.plcc.ci->low, std::tanh(std::atanh(r) - 1.96 / std::sqrt(7.0)), 1e-13);
  EXPECT_NEAR(s.plcc.ci->high, std::tanh(std::atanh(r) + 1.96 / std::sqrt(7.0)), 1e-13);

  ASSERT_TRUE(s.outlier_ratio.has_value());
  const double ratio = outliers / 10.0;
  EXPECT_EQ(s.outliers, static_cast<std::size_t>(outliers));
  EXPECT_DOUBLE_EQ(s.outlier_ratio->value, ratio);
  const double half = 1.96 * std::sqrt(ratio * (1 - ratio) / 10);
  EXPECT_NEAR(s.outlier_ratio->ci->low, std::max(0.0, ratio - half), 1e-15);
  EXPECT_NEAR(s.outlier_ratio->ci->high, std::min(1.0, ratio + half), 1e-15);
  EXPECT_GT(outliers, 0);  // the data set exercises both branches of max(0, ...)
  EXPECT_LT(outliers, 10);
}

TEST(P1401Statistics, RmseStarIsZeroInsideTheIntervals) {
  const std::vector<double> mos = {1, 2, 3, 4, 5};
  const std::vector<double> predicted = {1.1, 1.8, 3.0, 4.25, 4.9};
  const P1401Statistics s = p1401_statistics(predicted, mos, 0, {0.2, 0.2, 0.2, 0.3, 0.2});
  EXPECT_EQ(s.rmse_star->value, 0);
  EXPECT_EQ(s.outlier_ratio->value, 0);
  EXPECT_EQ(s.degrees_of_freedom, 5u);  // mapping none: d = 0
  EXPECT_NEAR(s.rmse.value, std::sqrt((0.01 + 0.04 + 0 + 0.0625 + 0.01) / 5), 1e-15);
}

TEST(P1401Statistics, WithoutIntervalsNoRmseStarNorOutliers) {
  const P1401Statistics s = p1401_statistics({1, 2, 3, 4}, {1.5, 2, 2.5, 4.5}, 2);
  EXPECT_FALSE(s.rmse_star.has_value());
  EXPECT_FALSE(s.outlier_ratio.has_value());
  EXPECT_TRUE(s.plcc.ci.has_value());
}

TEST(P1401Statistics, BadInputThrows) {
  EXPECT_THROW(p1401_statistics({1, 2, 3, 4}, {1, 2, 3, 4}, 4), NumericError);  // N = d
  EXPECT_THROW(p1401_statistics({1, 2, 3}, {1, 2}, 0), std::invalid_argument);
  EXPECT_THROW(p1401_statistics({1, 2, 3}, {1, 2, 3}, 0, {0.1, 0.2}), std::invalid_argument);
  EXPECT_THROW(p1401_statistics({1, kNaN, 3}, {1, 2, 3}, 0), NumericError);
  EXPECT_THROW(p1401_statistics({1, 2, 3}, {1, 2, 3}, 0, {0.1, -0.2, 0.1}), NumericError);
  EXPECT_THROW(p1401_statistics({1, 2, 3}, {1, 2, 3}, 0, {0.1, kNaN, 0.1}), NumericError);
}

TEST(P1401Statistics, MosConfidenceIntervalFromVotes) {
  // t(0.975, 14) = 2.1447866879178035 (see StudentTMatchesScipy): sd 0.8 over 15 votes.
  EXPECT_NEAR(mos_ci95(0.8, 15), 2.1447866879178035 * 0.8 / std::sqrt(15.0), 1e-14);
  EXPECT_EQ(mos_ci95(0, 4), 0);
  EXPECT_THROW(mos_ci95(0.5, 1), NumericError);
  EXPECT_THROW(mos_ci95(-0.5, 10), NumericError);
}

TEST(P1401Statistics, EvaluateIsFitThenStatistics) {
  const P1401Evaluation e = evaluate_p1401(kScores, kMos, Mapping::cubic, kCi95);
  const MappingFit fit = fit_mapping(kScores, kMos, Mapping::cubic);
  const P1401Statistics s = p1401_statistics(fit.predicted, kMos, 4, kCi95);
  EXPECT_EQ(e.fit.predicted, fit.predicted);
  EXPECT_EQ(e.statistics.degrees_of_freedom, 6u);
  EXPECT_EQ(e.statistics.rmse.value, s.rmse.value);
  EXPECT_EQ(e.statistics.rmse_star->value, s.rmse_star->value);
  EXPECT_EQ(e.statistics.plcc.ci->low, correlation_interval(s.plcc.value, 10)->low);
  EXPECT_FALSE(correlation_interval(0.5, 3).has_value());
  EXPECT_FALSE(correlation_interval(kNaN, 30).has_value());
}

// ---- significance tests -----------------------------------------------------------------------

TEST(P1401Tests, FisherZOnCorrelations) {
  // z = (atanh 0.9 - atanh 0.8) / sqrt(1/47 + 1/47); p = 2 norm.sf(z) (scipy).
  const SignificanceTest t = compare_correlations(0.9, 50, 0.8, 50);
  EXPECT_NEAR(t.statistic, (std::atanh(0.9) - std::atanh(0.8)) / std::sqrt(2.0 / 47), 1e-14);
  EXPECT_NEAR(t.statistic, 1.811128102461877, 1e-13);
  EXPECT_NEAR(t.p, 0.0701210243133152, 1e-14);
  const SignificanceTest swapped = compare_correlations(0.8, 50, 0.9, 50);
  EXPECT_NEAR(swapped.statistic, -t.statistic, 1e-15);
  EXPECT_NEAR(swapped.p, t.p, 1e-15);
  EXPECT_EQ(compare_correlations(1, 10, 1, 10).p, 1);
  EXPECT_TRUE(std::isfinite(compare_correlations(1, 10, 0.5, 10).statistic));
  EXPECT_THROW(compare_correlations(0.5, 3, 0.4, 10), NumericError);
  EXPECT_THROW(compare_correlations(1.5, 10, 0.4, 10), NumericError);
  EXPECT_THROW(compare_correlations(kNaN, 10, 0.4, 10), NumericError);
}

TEST(P1401Tests, FTestOnRmse) {
  // F = 0.5^2 / 0.4^2 = 1.5625 with (40, 38) dof; scipy f.sf(1.5625, 40, 38).
  const SignificanceTest t = compare_rmse(0.5, 40, 0.4, 38);
  EXPECT_NEAR(t.statistic, 1.5625, 1e-14);
  expect_relative(t.p, 0.08484590651300519, 1e-12);
  const SignificanceTest swapped = compare_rmse(0.4, 38, 0.5, 40);  // larger over smaller
  EXPECT_EQ(swapped.statistic, t.statistic);
  EXPECT_EQ(swapped.p, t.p);
  EXPECT_EQ(compare_rmse(0, 5, 0, 5).p, 1);
  EXPECT_EQ(compare_rmse(0.3, 5, 0, 5).p, 0);
  EXPECT_THROW(compare_rmse(0.3, 0, 0.2, 5), NumericError);
  EXPECT_THROW(compare_rmse(-0.3, 5, 0.2, 5), NumericError);
  EXPECT_THROW(compare_rmse(kNaN, 5, 0.2, 5), NumericError);
}

TEST(P1401Tests, TwoProportionTestOnOutlierRatios) {
  // Pooled (15 + 5) / 100 = 0.2; z = 0.2 / sqrt(0.2 * 0.8 * (1/50 + 1/50)) = 2.5;
  // p = 2 norm.sf(2.5) (scipy).
  const SignificanceTest t = compare_outlier_ratios(0.3, 50, 0.1, 50);
  EXPECT_NEAR(t.statistic, 2.5, 1e-14);
  EXPECT_NEAR(t.p, 0.012419330651552265, 1e-15);
  EXPECT_NEAR(compare_outlier_ratios(0.1, 50, 0.3, 50).statistic, -2.5, 1e-14);
  EXPECT_EQ(compare_outlier_ratios(0, 20, 0, 30).p, 1);
  EXPECT_EQ(compare_outlier_ratios(1, 20, 1, 30).p, 1);
  EXPECT_THROW(compare_outlier_ratios(0.3, 0, 0.1, 50), NumericError);
  EXPECT_THROW(compare_outlier_ratios(1.3, 10, 0.1, 50), NumericError);
}

TEST(P1401Tests, CompareTwoEvaluations) {
  const P1401Statistics a = evaluate_p1401(kScores, kMos, Mapping::linear, kCi95).statistics;
  std::vector<double> worse = kScores;
  std::swap(worse[2], worse[7]);  // a model that misranks two stimuli
  const P1401Statistics b = evaluate_p1401(worse, kMos, Mapping::linear, kCi95).statistics;
  const P1401Comparison c = compare_p1401(a, b);
  const SignificanceTest plcc = compare_correlations(a.plcc.value, 10, b.plcc.value, 10);
  EXPECT_EQ(c.plcc.statistic, plcc.statistic);
  EXPECT_GT(c.plcc.statistic, 0);  // a is the better model
  EXPECT_EQ(c.rmse.p, compare_rmse(a.rmse.value, 8, b.rmse.value, 8).p);
  ASSERT_TRUE(c.rmse_star && c.outlier_ratio);
  EXPECT_EQ(c.rmse_star->statistic,
            compare_rmse(a.rmse_star->value, 8, b.rmse_star->value, 8).statistic);
  EXPECT_EQ(c.outlier_ratio->p,
            compare_outlier_ratios(a.outlier_ratio->value, 10, b.outlier_ratio->value, 10).p);
  const P1401Statistics no_ci = evaluate_p1401(worse, kMos, Mapping::linear).statistics;
  EXPECT_FALSE(compare_p1401(a, no_ci).rmse_star.has_value());
}

}  // namespace
}  // namespace qm3d
