// The eight local features shared by CMDM (Nehme et al., "Color-Mesh Distortion Measure",
// 2020/2021, eqs. 1.5-1.8) and PCQM (Meynet et al., QoMEX 2020): three curvature features and
// five colour features (iCID form: lightness, lightness contrast, lightness structure, chroma,
// hue). Every feature is a distortion: 0 for identical neighbourhoods.
#pragma once

#include <array>
#include <vector>

#include "qm3d/common/statistics.h"

namespace qm3d {

/// f1..f8 (index 0..7).
using FeatureVector = std::array<double, 8>;
inline constexpr std::size_t kNumFeatures = 8;

namespace constants {
/// k in f1..f3 (CMDM paper "k = 1"; MEPP2 cmdm.h `+ 1`; PCQM `constant_curvature = 1.0`).
inline constexpr double kCurvatureStabilizer = 1.0;
/// iCID constants c1..c5 (CMDM paper Table 1.1; MEPP2 cmdm.h; PCQM `constant_1..5`).
inline constexpr double kLightnessC1 = 0.002;
inline constexpr double kLightnessContrastC2 = 0.1;
inline constexpr double kLightnessStructureC3 = 0.1;
inline constexpr double kChromaC4 = 0.002;
inline constexpr double kHueC5 = 0.008;
}  // namespace constants

/// f1 = |mu1 - mu2| / (max(mu1, mu2) + k): curvature comparison.
double curvature_comparison(double mean1, double mean2);
/// f2 = |sd1 - sd2| / (max(sd1, sd2) + k): curvature contrast.
double curvature_contrast(double sd1, double sd2);
/// f3 = |sd1 sd2 - cov12| / (sd1 sd2 + k): curvature structure.
double curvature_structure(double sd1, double sd2, double cov12);

/// 1 / (c1 dL^2 + 1): lightness similarity (f4 = 1 - it).
double lightness_similarity(double mean1, double mean2);
/// (2 sd1 sd2 + c2) / (sd1^2 + sd2^2 + c2): lightness-contrast similarity (f5 = 1 - it).
double lightness_contrast_similarity(double sd1, double sd2);
/// (cov12 + c3) / (sd1 sd2 + c3): lightness-structure similarity (f6 = 1 - it).
double lightness_structure_similarity(double sd1, double sd2, double cov12);
/// 1 / (c4 dC^2 + 1): chroma similarity (f7 = 1 - it).
double chroma_similarity(double mean1, double mean2);
/// 1 / (c5 mean_dH^2 + 1): hue similarity (f8 = 1 - it).
double hue_similarity(double mean_hue_difference);

/// The paired samples of one neighbourhood. Index 1 = the element's own side (the object being
/// iterated), 2 = its image on the other object. All vectors have the same length.
struct NeighbourhoodSamples {
  std::vector<double> w1, w2;          ///< Gaussian weights of each sample on each side
  std::vector<double> curv1, curv2;    ///< processed curvature
  std::vector<double> light1, light2;  ///< LAB2000HL lightness
  std::vector<double> chroma1, chroma2;
  std::vector<double> hue_diff;  ///< per-pair hue difference (averaged with w1)

  std::size_t size() const { return w1.size(); }
  void clear();
};

/// How each reference computes its statistics (SPEC-CMDM 1.8 and 2, SPEC-PCQM 1.5).
struct FeatureConventions {
  CovarianceConvention curvature_covariance;
  bool cap_curvature_structure = false;         ///< f3 <- min(f3, 1)               (PCQM)
  bool unweighted_lightness_structure = false;  ///< sL1, sL2, sL12 unweighted (PCQM)
  CovarianceConvention lightness_covariance;    ///< when weighted
};

/// CMDM (MEPP2 cmdm.h): w1 covariances clamped at 0.
inline constexpr FeatureConventions kCmdmConventions{
    {CovarianceWeighting::kFirst, true}, false, false, {CovarianceWeighting::kFirst, true}};
/// PCQM (main.cpp): w1 curvature covariance, f3 capped at 1, unweighted lightness structure.
inline constexpr FeatureConventions kPcqmConventions{
    {CovarianceWeighting::kFirst, false}, true, true, {CovarianceWeighting::kFirst, false}};
/// MSDM2 (MEPP2 msdm2.h): mixed-weight, unclamped covariance (curvature features only).
inline constexpr FeatureConventions kMsdm2Conventions{
    {CovarianceWeighting::kMixed, false}, false, false, {CovarianceWeighting::kMixed, false}};

/// f1..f3 of a neighbourhood (the other five entries are left 0).
FeatureVector curvature_features(const NeighbourhoodSamples& s, const FeatureConventions& conv);
/// s4..s8 of a neighbourhood: the similarities whose complements 1 - s are f4..f8 (entries
/// 3..7; the first three entries are left 0).
FeatureVector color_similarities(const NeighbourhoodSamples& s, const FeatureConventions& conv);
/// f4..f8 of a neighbourhood (the first three entries are left 0).
FeatureVector color_features(const NeighbourhoodSamples& s, const FeatureConventions& conv);
/// All eight features of a neighbourhood. `s` must not be empty.
FeatureVector local_features(const NeighbourhoodSamples& s, const FeatureConventions& conv);
/// f1..f3 followed by s4..s8 (the similarities, not their complements): what PCQM pools
/// (pooling.h, mean_features_from_similarities). `s` must not be empty.
FeatureVector local_features_and_similarities(const NeighbourhoodSamples& s,
                                              const FeatureConventions& conv);
/// Turns f1..f3, s4..s8 into f1..f8 (entries 3..7 become 1 - s, as color_features computes them).
void similarities_to_features(FeatureVector& v);

}  // namespace qm3d
