// SSIM and MS-SSIM of two grey images (the luma of rendered views), pooled over a mask.
//
// SSIM (Wang, Bovik, Sheikh, Simoncelli 2004, eq. 13) as scikit-image 0.19's
// structural_similarity(gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
// data_range=255): local means, variances and covariance from a separable Gaussian (sigma 1.5,
// radius int(3.5 sigma + 0.5) = 5, weights normalised to sum 1, scipy's 'reflect' borders: the
// edge pixel repeated), K1 = 0.01, K2 = 0.03, population covariances. The map S is skimage's
// `full=True` map, computed over the whole image (borders reflected at the image's edges, not
// the mask's). The pooled SSIM is the plain mean of S over the mask's pixels (in ibsm: the
// pixels both views cover); pixels outside the mask still enter the windows of mask pixels
// within 5 px. skimage's own mean_ssim instead crops a (win_size - 1) / 2 = 5 px border of
// the whole image and averages every remaining pixel: on a rendered view the mask replaces
// that crop (a test: python/tests/test_ibsm_ssim.py, S from skimage, mean over the mask).
// S is invariant to flipping the image vertically (symmetric window and borders), so views
// stored bottom row first score as their top-row-first PNGs (to rounding).
//
// MS-SSIM (Wang, Simoncelli, Bovik 2003, eq. 7): M = 5 scales with exponents
// beta = gamma = (0.0448, 0.2856, 0.3001, 0.2363, 0.1333), alpha_M = beta_M:
//   MS-SSIM = l_M^alpha_M * prod_j cs_j^beta_j,
// cs_j the mean over scale j's mask of (2 s_ab + C2) / (s_a^2 + s_b^2 + C2), l_M the mean of
// (2 m_a m_b + C1) / (m_a^2 + m_b^2 + C1) at the coarsest scale (the same Gaussian window at
// every scale). Between scales both images are low-passed and halved by 2x2 block means (an odd
// last row or column dropped) and the mask keeps a block only where all four pixels were in it.
// (A vertically flipped odd-height image drops its other edge row: with ibsm's bottom-first
// rows, an odd height drops the PNG's top row.)
// A negative mean cs_j (anti-correlated structure) is taken as 0, as common implementations
// do (the power of a negative number is not real).
#pragma once

#include <cstdint>
#include <vector>

namespace qm3d::render {

/// A grey image, rows in order, values in [0, 255].
struct GreyImage {
  int width = 0;
  int height = 0;
  std::vector<double> values;  ///< width * height, row-major
};

/// scikit-image's SSIM map S (one value per pixel). std::invalid_argument for images of
/// different sizes.
std::vector<double> ssim_map(const GreyImage& a, const GreyImage& b);

/// The mean of the SSIM map over the pixels where mask != 0 (the map is computed only around
/// them: the same values). NaN when the mask is empty.
double masked_ssim(const GreyImage& a, const GreyImage& b, const std::vector<std::uint8_t>& mask);

/// MS-SSIM over the mask (header comment). NaN when the mask is empty at some scale.
double masked_ms_ssim(const GreyImage& a, const GreyImage& b,
                      const std::vector<std::uint8_t>& mask);

/// Both scores at once: masked_ssim and masked_ms_ssim's values (bit for bit), the full-scale
/// filtering done once (about 40% less time than the two calls).
struct SsimScores {
  double ssim = 0;
  double ms_ssim = 0;
};
SsimScores masked_ssim_scores(const GreyImage& a, const GreyImage& b,
                              const std::vector<std::uint8_t>& mask);

/// Scales and exponents of MS-SSIM (Wang et al. 2003, section 3.2).
constexpr int kMsSsimScales = 5;
constexpr double kMsSsimWeights[kMsSsimScales] = {0.0448, 0.2856, 0.3001, 0.2363, 0.1333};

}  // namespace qm3d::render
