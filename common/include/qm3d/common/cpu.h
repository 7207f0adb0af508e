// What the processor running qm3d can do, for the few loops that pick a vector path at run time
// (the choice never changes a value: each path computes lane by lane what the scalar one does,
// or is documented where it does not, e.g. gaussian_weights_in_place).
#pragma once

namespace qm3d {

/// Whether the processor has AVX2 (asked once; false off x86-64).
inline bool cpu_has_avx2() {
#if defined(__GNUC__) && defined(__x86_64__)
  static const bool yes = __builtin_cpu_supports("avx2");
  return yes;
#else
  return false;
#endif
}

}  // namespace qm3d
