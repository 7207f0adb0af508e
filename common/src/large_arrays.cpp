#include "qm3d/common/large_arrays.h"

#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>

namespace qm3d {
namespace {

/// QM3D_HUGE_PAGES=1 in the environment turns the advice on (read once).
///
/// Off by default: on virtual machines whose balloon driver reports free memory to the host
/// (virtio-balloon free page reporting, as on the 2-vCPU development VMs), the free blocks of
/// 2 MiB are exactly what the host has taken back, so every huge page is faulted in from the
/// host while the guest zeroes it: 2 s for 256 MiB against 0.1-0.2 s in 4 KiB pages, which come
/// from smaller free blocks that the host still backs (docs/profile.md, eighth round).
bool huge_pages_wanted() {
  static const bool wanted = [] {
    const char* v = std::getenv("QM3D_HUGE_PAGES");
    return v != nullptr && std::strcmp(v, "1") == 0;
  }();
  return wanted;
}

}  // namespace

void advise_huge_pages(const void* data, std::size_t bytes) {
#ifdef MADV_HUGEPAGE
  if (!huge_pages_wanted()) return;
  constexpr std::uintptr_t kHugePage = std::uintptr_t{2} << 20;
  if (data == nullptr || bytes < 2 * kHugePage) return;
  const auto start = reinterpret_cast<std::uintptr_t>(data);
  const std::uintptr_t begin = (start + kHugePage - 1) & ~(kHugePage - 1);
  const std::uintptr_t end = (start + bytes) & ~(kHugePage - 1);
  // A hint: an error (no THP support, a range the kernel will not advise) changes nothing.
  if (end > begin) (void)::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
  (void)data;
  (void)bytes;
#endif
}

}  // namespace qm3d
