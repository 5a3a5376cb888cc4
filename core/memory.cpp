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

void release_freed_memory() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

bool release_freed_memory_if_large() {
#ifdef __GLIBC__
  const std::uint64_t physical = physical_memory();
  if (physical == 0 || mallinfo2().fordblks <= physical / 8) return false;
  malloc_trim(0);
  return true;
#else
  return false;
#endif
}

std::string out_of_memory_message(const std::string& what) {
  rlimit limit;
  if (what.find("out of memory") == std::string::npos || what.find("ulimit") != std::string::npos ||
      getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY)
    return what;
  return what + " under the address-space limit (ulimit -v) of " + std::to_string(limit.rlim_cur >> 20) +
         " MB: raise the limit";
}

}  // namespace msd
