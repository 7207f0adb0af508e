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

// s4..s8 into `sim` from the lightness moments and the weighted means of chroma and hue.
void color_similarities_of(const NeighbourhoodSamples& s, const FeatureConventions& conv,
                           const PairedMoments& light, double chroma_mean1, double chroma_mean2,
                           double hue_mean, FeatureVector& sim) {
  const PairedMoments structure =
      conv.unweighted_lightness_structure ? unweighted_moments(s.light1, s.light2) : light;
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
  color_similarities_of(s, conv,
                        weighted_moments(s.light1, s.light2, s.w1, s.w2, conv.lightness_covariance),
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

FeatureVector local_features_and_similarities(const NeighbourhoodSamples& s,
                                              const FeatureConventions& conv) {
  // curvature_features and color_similarities with every first-moment sum taken in one pass
  // over the samples (the sums of w1 and w2 once instead of four times): each sum accumulates
  // the same terms in the same order, so the values are theirs, bit for bit.
  double sw1 = 0, sw2 = 0, c1 = 0, c2 = 0, l1 = 0, l2 = 0, ch1 = 0, ch2 = 0, hue = 0;
  for (std::size_t i = 0; i < s.w1.size(); ++i) {
    const double w1 = s.w1[i], w2 = s.w2[i];
    sw1 += w1;
    sw2 += w2;
    c1 += s.curv1[i] * w1;
    c2 += s.curv2[i] * w2;
    l1 += s.light1[i] * w1;
    l2 += s.light2[i] * w2;
    ch1 += s.chroma1[i] * w1;
    ch2 += s.chroma2[i] * w2;
    hue += s.hue_diff[i] * w1;
  }
  FeatureVector f = curvature_features_of(
      weighted_moments_from_sums(s.curv1, s.curv2, s.w1, s.w2, sw1, sw2, c1, c2,
                                 conv.curvature_covariance),
      conv);
  color_similarities_of(s, conv,
                        weighted_moments_from_sums(s.light1, s.light2, s.w1, s.w2, sw1, sw2, l1,
                                                   l2, conv.lightness_covariance),
                        ch1 / sw1, ch2 / sw2, hue / sw1, f);
  return f;
}

FeatureVector local_features(const NeighbourhoodSamples& s, const FeatureConventions& conv) {
  FeatureVector f = local_features_and_similarities(s, conv);
  similarities_to_features(f);
  return f;
}

}  // namespace qm3d
