// gaussian_weights_in_place: the Gaussian weights of a neighbourhood's samples in one pass, with
// a vector exponential where the machine has one (about a tenth of CMDM's and PCQM's time went to
// one std::exp per weight; docs/profile.md).
#include <cmath>
#include <cstddef>

#include "qm3d/common/cpu.h"
#include "qm3d/common/statistics.h"

#if defined(QM3D_HAVE_LIBMVEC_AVX2)
#include <immintrin.h>

// glibc's libmvec: exp on 4 doubles (x86-64 vector ABI name, AVX2), at most 4 ulp from the
// correctly rounded value (glibc manual, "Errors in Math Functions").
extern "C" __m256d _ZGVdN4v_exp(__m256d);
#endif

namespace qm3d {
namespace {

#if defined(QM3D_HAVE_LIBMVEC_AVX2)
// Four weights from squared distances s: -s / 2.0 / sigma / sigma and the scale times exp,
// operation for operation as gaussian_weight writes them (IEEE vector operations round like
// scalar ones).
__attribute__((target("avx2"))) inline __m256d four_weights_from_squares(__m256d s, __m256d sigma,
                                                                         __m256d scale) {
  const __m256d sign = _mm256_set1_pd(-0.0);
  __m256d e = _mm256_xor_pd(s, sign);
  e = _mm256_div_pd(_mm256_div_pd(_mm256_div_pd(e, _mm256_set1_pd(2.0)), sigma), sigma);
  return _mm256_mul_pd(scale, _ZGVdN4v_exp(e));
}

// Four weights from distances d: s = d * d, then as above.
__attribute__((target("avx2"))) inline __m256d four_weights(__m256d d, __m256d sigma,
                                                            __m256d scale) {
  return four_weights_from_squares(_mm256_mul_pd(d, d), sigma, scale);
}

template <bool kSquares>
__attribute__((target("avx2"))) void weights_avx2(double* values, std::size_t n, double sigma) {
  const __m256d s = _mm256_set1_pd(sigma);
  const __m256d scale = _mm256_set1_pd(gaussian_weight_scale(sigma));
  const auto four = [&](__m256d x) __attribute__((target("avx2"))) {
    return kSquares ? four_weights_from_squares(x, s, scale) : four_weights(x, s, scale);
  };
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) _mm256_storeu_pd(values + i, four(_mm256_loadu_pd(values + i)));
  if (i == n) return;
  // The tail through the same lanes, so that an element's weight does not depend on where it
  // stands (the walk tests compare samples gathered in different orders bit for bit).
  double tail[4] = {0, 0, 0, 0};
  for (std::size_t k = i; k < n; ++k) tail[k - i] = values[k];
  _mm256_storeu_pd(tail, four(_mm256_loadu_pd(tail)));
  for (std::size_t k = i; k < n; ++k) values[k] = tail[k - i];
}
#endif

// The weights of distances (kSquares false) or squared distances, in place: the vector
// exponential where the machine has it, else gaussian_weight's own scalar operations.
template <bool kSquares>
void weights_in_place(double* values, std::size_t n, double sigma) {
#if defined(QM3D_HAVE_LIBMVEC_AVX2)
  if (cpu_has_avx2()) {
    weights_avx2<kSquares>(values, n, sigma);
    return;
  }
#endif
  for (std::size_t i = 0; i < n; ++i) {
    values[i] = kSquares ? gaussian_weight_from_square(values[i], sigma)
                         : gaussian_weight(values[i], sigma);
  }
}

}  // namespace

void gaussian_weights_in_place(double* values, std::size_t n, double sigma) {
  weights_in_place<false>(values, n, sigma);
}

void gaussian_weights_from_squares_in_place(double* values, std::size_t n, double sigma) {
  weights_in_place<true>(values, n, sigma);
}

}  // namespace qm3d
