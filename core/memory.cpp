#include "msdeform/core/memory.h"

#include <malloc.h>
#include <sys/resource.h>
#include <unistd.h>

namespace msd {

std::uint64_t physical_memory() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  return pages > 0 && page > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page) : 0;
}

void retain_freed_memory() {
  rlimit limit;
  if (getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur != RLIM_INFINITY) return;
  mallopt(M_MMAP_MAX, 0);                 // serve large blocks from the heap ...
  mallopt(M_TRIM_THRESHOLD, 1 << 30);     // ... keep up to 1 GiB of free heap top (then trim to M_TOP_PAD) ...
  mallopt(M_TOP_PAD, 256 << 20);          // ... and grow it in 256 MiB steps.
}

}  // namespace msd
