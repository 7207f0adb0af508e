#include "qm3d/common/features.h"

#include <algorithm>
#include <cmath>

namespace qm3d {

using namespace constants;

double curvature_comparison(double mean1, double mean2) {
  return std::fabs(mean1 - mean2) / (std::max(mean1, mean2) + kCurvatureStabilizer);
}

double curvature_contrast(double sd1, double sd2) {
  return std::fabs(sd1 - sd2) / (std::max(sd1, sd2) + kCurvatureStabilizer);
}

double curvature_structure(double sd1, double sd2, double cov12) {
  return std::fabs(sd1 * sd2 - cov12) / (sd1 * sd2 + kCurvatureStabilizer);
}

double lightness_similarity(double mean1, double mean2) {
  const double d = mean1 - mean2;
  return 1.0 / (kLightnessC1 * d * d + 1.0);
}

double lightness_contrast_similarity(double sd1, double sd2) {
  return (2.0 * sd1 * sd2 + kLightnessContrastC2) / (sd1 * sd1 + sd2 * sd2 + kLightnessContrastC2);
}

double lightness_structure_similarity(double sd1, double sd2, double cov12) {
  return (cov12 + kLightnessStructureC3) / (sd1 * sd2 + kLightnessStructureC3);
}

double chroma_similarity(double mean1, double mean2) {
  const double d = mean1 - mean2;
  return 1.0 / (kChromaC4 * d * d + 1.0);
}

double hue_similarity(double mean_hue_difference) {
  return 1.0 / (kHueC5 * mean_hue_difference * mean_hue_difference + 1.0);
}

void NeighbourhoodSamples::clear() {
  for (auto* v : {&w1, &w2, &curv1, &curv2, &light1, &light2, &chroma1, &chroma2, &hue_diff}) {
    v->clear();
  }
}

namespace {

// f1..f3 from the curvature moments.
FeatureVector curvature_features_of(const PairedMoments& m, const FeatureConventions& conv) {
  FeatureVector f{};
  f[0] = curvature_comparison(m.mean1, m.mean2);
  f[1] = curvature_contrast(m.sd1, m.sd2);
  f[2] = curvature_structure(m.sd1, m.sd2, m.cov12);
  if (conv.cap_curvature_structure) f[2] = std::min(f[2], 1.0);
  return f;
}

// s4..s8 into `sim` from the lightness moments, those of the structure term (the unweighted
// ones under unweighted_lightness_structure, else `light`) and the weighted means of chroma and
// hue.
void color_similarities_of(const PairedMoments& light, const PairedMoments& structure,
                           double chroma_mean1, double chroma_mean2, double hue_mean,
                           FeatureVector& sim) {
  sim[3] = lightness_similarity(light.mean1, light.mean2);
  sim[4] = lightness_contrast_similarity(light.sd1, light.sd2);
  sim[5] = lightness_structure_similarity(structure.sd1, structure.sd2, structure.cov12);
  sim[6] = chroma_similarity(chroma_mean1, chroma_mean2);
  sim[7] = hue_similarity(hue_mean);
}

}  // namespace

FeatureVector curvature_features(const NeighbourhoodSamples& s, const FeatureConventions& conv) {
  return curvature_features_of(
      weighted_moments(s.curv1, s.curv2, s.w1, s.w2, conv.curvature_covariance), conv);
}

FeatureVector color_similarities(const NeighbourhoodSamples& s, const FeatureConventions& conv) {
  FeatureVector sim{};
  const PairedMoments light =
      weighted_moments(s.light1, s.light2, s.w1, s.w2, conv.lightness_covariance);
  color_similarities_of(
      light, conv.unweighted_lightness_structure ? unweighted_moments(s.light1, s.light2) : light,
      weighted_mean(s.chroma1, s.w1), weighted_mean(s.chroma2, s.w2),
      weighted_mean(s.hue_diff, s.w1), sim);
  return sim;
}

void similarities_to_features(FeatureVector& v) {
  for (std::size_t k = 3; k < kNumFeatures; ++k) v[k] = 1.0 - v[k];
}

FeatureVector color_features(const NeighbourhoodSamples& s, const FeatureConventions& conv) {
  FeatureVector f = color_similarities(s, conv);
  similarities_to_features(f);
  return f;
}

namespace {

// The sums of local_features_and_similarities' first pass, each accumulated in sample order.
struct FirstMoments {
  double w1 = 0, w2 = 0, curv1 = 0, curv2 = 0, light1 = 0, light2 = 0, chroma1 = 0, chroma2 = 0,
         hue = 0;
  double plain_light1 = 0, plain_light2 = 0;  ///< unweighted sums (kPlain only)
};

// Both passes of weighted_moments_from_sums for the curvatures and the lightnesses, and with
// kPlain those of unweighted_moments for the lightnesses too, in two loops over the samples:
// every sum accumulates the same terms in the same order as in those functions (same bits),
// but the independent sums advance together instead of one pass per statistic.
template <bool kPlain>
void paired_moments(const NeighbourhoodSamples& s, const FeatureConventions& conv,
                    PairedMoments& curv, PairedMoments& light, PairedMoments& plain,
                    FirstMoments& a) {
  const std::size_t n = s.w1.size();
  for (std::size_t i = 0; i < n; ++i) {
    const double w1 = s.w1[i], w2 = s.w2[i];
    a.w1 += w1;
    a.w2 += w2;
    a.curv1 += s.curv1[i] * w1;
    a.curv2 += s.curv2[i] * w2;
    a.light1 += s.light1[i] * w1;
    a.light2 += s.light2[i] * w2;
    a.chroma1 += s.chroma1[i] * w1;
    a.chroma2 += s.chroma2[i] * w2;
    a.hue += s.hue_diff[i] * w1;
    if (kPlain) {
      a.plain_light1 += s.light1[i];
      a.plain_light2 += s.light2[i];
    }
  }
  const double count = static_cast<double>(n);
  const double cm1 = a.curv1 / a.w1, cm2 = a.curv2 / a.w2;
  const double lm1 = a.light1 / a.w1, lm2 = a.light2 / a.w2;
  const double pm1 = a.plain_light1 / count, pm2 = a.plain_light2 / count;
  const double* wc = conv.curvature_covariance.weighting == CovarianceWeighting::kFirst
                         ? s.w1.data()
                         : s.w2.data();
  const double* wl = conv.lightness_covariance.weighting == CovarianceWeighting::kFirst
                         ? s.w1.data()
                         : s.w2.data();
  double cv1 = 0, cv2 = 0, ccov = 0, lv1 = 0, lv2 = 0, lcov = 0, pv1 = 0, pv2 = 0, pcov = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double w1 = s.w1[i], w2 = s.w2[i];
    const double c1 = s.curv1[i] - cm1, c2 = s.curv2[i] - cm2;
    cv1 += w1 * c1 * c1;
    cv2 += w2 * c2 * c2;
    ccov += wc[i] * c1 * c2;
    const double l1 = s.light1[i] - lm1, l2 = s.light2[i] - lm2;
    lv1 += w1 * l1 * l1;
    lv2 += w2 * l2 * l2;
    lcov += wl[i] * l1 * l2;
    if (kPlain) {
      const double p1 = s.light1[i] - pm1, p2 = s.light2[i] - pm2;
      pv1 += p1 * p1;
      pv2 += p2 * p2;
      pcov += p1 * p2;
    }
  }
  curv = weighted_moments_finish(cm1, cm2, cv1, cv2, ccov, a.w1, a.w2, conv.curvature_covariance);
  light = weighted_moments_finish(lm1, lm2, lv1, lv2, lcov, a.w1, a.w2, conv.lightness_covariance);
  if (kPlain) plain = unweighted_moments_finish(pm1, pm2, pv1, pv2, pcov, count);
}

}  // namespace

FeatureVector local_features_and_similarities(const NeighbourhoodSamples& s,
                                              const FeatureConventions& conv) {
  // curvature_features and color_similarities with the sums of every statistic taken in two
  // passes over the samples (paired_moments): the values are theirs, bit for bit.
  PairedMoments curv, light, plain;
  FirstMoments a;
  if (conv.unweighted_lightness_structure) {
    paired_moments<true>(s, conv, curv, light, plain, a);
  } else {
    paired_moments<false>(s, conv, curv, light, plain, a);
  }
  FeatureVector f = curvature_features_of(curv, conv);
  color_similarities_of(light, conv.unweighted_lightness_structure ? plain : light,
                        a.chroma1 / a.w1, a.chroma2 / a.w2, a.hue / a.w1, f);
  return f;
}

FeatureVector local_features(const NeighbourhoodSamples& s, const FeatureConventions& conv) {
  FeatureVector f = local_features_and_similarities(s, conv);
  similarities_to_features(f);
  return f;
}

}  // namespace qm3d
