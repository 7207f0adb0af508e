#include "qm3d/common/error.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>

namespace qm3d {

std::size_t memory_limit_bytes() {
  std::size_t limit = 0;
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page_size = sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && page_size > 0) limit = std::size_t(pages) * std::size_t(page_size);
  rlimit as{};
  if (getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY) {
    const std::size_t cap = static_cast<std::size_t>(as.rlim_cur);
    limit = limit == 0 ? cap : std::min(limit, cap);
  }
  return limit;
}

}  // namespace qm3d
