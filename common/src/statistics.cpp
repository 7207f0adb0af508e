#include "qm3d/common/statistics.h"

#include <cmath>

namespace qm3d {

double population_sd(const std::vector<double>& x, double mean) {
  double sum = 0;
  for (double v : x) sum += (v - mean) * (v - mean);
  return std::sqrt(sum / static_cast<double>(x.size()));
}

double weighted_mean(const std::vector<double>& x, const std::vector<double>& w) {
  double sum_w = 0;
  double sum_wx = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sum_w += w[i];
    sum_wx += x[i] * w[i];
  }
  return sum_wx / sum_w;
}

PairedMoments weighted_moments(const std::vector<double>& x1, const std::vector<double>& x2,
                               const std::vector<double>& w1, const std::vector<double>& w2,
                               const CovarianceConvention& convention) {
  double sum_w1 = 0, sum_w2 = 0, sum_x1 = 0, sum_x2 = 0;
  for (std::size_t i = 0; i < x1.size(); ++i) {
    sum_w1 += w1[i];
    sum_w2 += w2[i];
    sum_x1 += x1[i] * w1[i];
    sum_x2 += x2[i] * w2[i];
  }
  return weighted_moments_from_sums(x1, x2, w1, w2, sum_w1, sum_w2, sum_x1, sum_x2, convention);
}

PairedMoments weighted_moments_from_sums(const std::vector<double>& x1,
                                         const std::vector<double>& x2,
                                         const std::vector<double>& w1,
                                         const std::vector<double>& w2, double sum_w1,
                                         double sum_w2, double sum_x1, double sum_x2,
                                         const CovarianceConvention& convention) {
  const double mean1 = sum_x1 / sum_w1;
  const double mean2 = sum_x2 / sum_w2;
  double var1 = 0, var2 = 0, cov = 0;
  const auto& wc = convention.weighting == CovarianceWeighting::kFirst ? w1 : w2;
  for (std::size_t i = 0; i < x1.size(); ++i) {
    const double d1 = x1[i] - mean1;
    const double d2 = x2[i] - mean2;
    var1 += w1[i] * d1 * d1;
    var2 += w2[i] * d2 * d2;
    cov += wc[i] * d1 * d2;
  }
  return weighted_moments_finish(mean1, mean2, var1, var2, cov, sum_w1, sum_w2, convention);
}

PairedMoments weighted_moments_finish(double mean1, double mean2, double var1, double var2,
                                      double cross, double sum_w1, double sum_w2,
                                      const CovarianceConvention& convention) {
  PairedMoments m;
  m.mean1 = mean1;
  m.mean2 = mean2;
  m.sd1 = std::sqrt(var1 / sum_w1);
  m.sd2 = std::sqrt(var2 / sum_w2);
  m.cov12 = cross / sum_w1;
  if (convention.clamp_at_zero && m.cov12 < 0) m.cov12 = 0;
  return m;
}

PairedMoments unweighted_moments(const std::vector<double>& x1, const std::vector<double>& x2) {
  const double n = static_cast<double>(x1.size());
  double sum1 = 0, sum2 = 0;
  for (std::size_t i = 0; i < x1.size(); ++i) {
    sum1 += x1[i];
    sum2 += x2[i];
  }
  const double mean1 = sum1 / n;
  const double mean2 = sum2 / n;
  double var1 = 0, var2 = 0, cov = 0;
  for (std::size_t i = 0; i < x1.size(); ++i) {
    const double d1 = x1[i] - mean1;
    const double d2 = x2[i] - mean2;
    var1 += d1 * d1;
    var2 += d2 * d2;
    cov += d1 * d2;
  }
  return unweighted_moments_finish(mean1, mean2, var1, var2, cov, n);
}

PairedMoments unweighted_moments_finish(double mean1, double mean2, double var1, double var2,
                                        double cross, double n) {
  PairedMoments m;
  m.mean1 = mean1;
  m.mean2 = mean2;
  m.sd1 = std::sqrt(var1 / n);
  m.sd2 = std::sqrt(var2 / n);
  m.cov12 = cross / n;
  return m;
}

}  // namespace qm3d
