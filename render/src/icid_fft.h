// A complex DFT of one length applied to several sequences at once, for iCID's CSF filtering
// (icid_csf.cpp). Private to render/src.
#pragma once

#include <vector>

namespace qm3d::render::icid_detail {

/// The DFT of length n of kLanes sequences together, in split layout: element k of sequence
/// (lane) c at re[k * kLanes + c], im[k * kLanes + c]. Mixed-radix Stockham (self-sorting,
/// decimation in time; Van Loan, "Computational Frameworks for the FFT", 1992, 1.7) with
/// radix-8, -4, -2 and -3 butterflies and a generic odd-prime one, twiddles precomputed. Every lane
/// gets the same operations in the same order, so the innermost loops over the lanes vectorise
/// (SSE2, and AVX2 without FMA through target_clones: the same bits on any CPU) and a lane's
/// result does not depend on its neighbours or on the thread. The plan is immutable (share it);
/// the work buffers are the caller's.
class BatchFft {
 public:
  /// 4: one AVX2 vector a lane group, and a 768-point block of 4 lanes and its work space
  /// (98 KB) stay near the core; 8 lanes measured ~25 % slower in all, 2 lanes ~10 %.
  static constexpr int kLanes = 4;
  /// Prime factors up to this go through a butterfly; lengths with larger ones are not planned.
  static constexpr int kMaxRadix = 13;

  /// Whether n's prime factors are all <= kMaxRadix (and n >= 1).
  static bool supported(int n);

  /// A plan for length n (supported(n)); the factor 3 goes last when n has one, for
  /// inverse_centre_third.
  explicit BatchFft(int n);

  int size() const { return n_; }

  /// A block of kLanes sequences (re, im: n * kLanes doubles each) and as much work space. A
  /// transform leaves its result in (re, im): the stages go back and forth between the two
  /// pairs, and where the result ends in the work pair the pointers are exchanged, no copy.
  struct Buffers {
    double *re, *im, *work_re, *work_im;
  };

  /// Unscaled: X_k = sum_j x_j exp(-2 pi i j k / n).
  void forward(Buffers& b) const;

  /// Scaled by 1 / n (x_j = sum_k X_k exp(2 pi i j k / n) / n). With `centre_third` (n divisible
  /// by 3) only the outputs n/3 .. 2n/3 - 1 are computed (the rest is left undefined): the last
  /// radix-3 stage computes only its middle output.
  void inverse(Buffers& b, bool centre_third = false) const;

  /// The inverse DFT unscaled (x_j = sum_k X_k exp(2 pi i j k / n)), for callers that fold the
  /// 1 / n into constants of their own.
  void inverse_unscaled(Buffers& b) const;

 private:
  struct Stage {
    int radix = 0;
    int before = 0;  ///< L: the length of the transforms this stage combines
    int after = 0;   ///< n / (L radix): the number of transforms after it
    std::vector<double> twiddle_re, twiddle_im;  ///< [j * (radix - 1) + t - 1] = w_{L radix}^{j t}
  };

  /// The stages from (xr, xi) on; true when the result ends in (yr, yi).
  bool run(double* xr, double* xi, double* yr, double* yi, bool centre_third) const;

  int n_ = 0;
  std::vector<Stage> stages_;
};

}  // namespace qm3d::render::icid_detail
