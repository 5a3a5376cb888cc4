#include "msdeform/core/memory.h"

#include <cstdlib>
#include <fstream>

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

std::uint64_t cgroup_memory_limit() {
  std::ifstream groups("/proc/self/cgroup");
  std::string line;
  std::uint64_t limit = 0;
  while (std::getline(groups, line)) {  // "0::/path" (v2) or "N:memory:/path" (v1)
    const auto a = line.find(':'), b = a == std::string::npos ? a : line.find(':', a + 1);
    if (b == std::string::npos) continue;
    const std::string id = line.substr(0, a), controllers = line.substr(a + 1, b - a - 1),
                      path = line.substr(b + 1);
    std::string file;
    if (id == "0" && controllers.empty())
      file = "/sys/fs/cgroup" + path + "/memory.max";
    else if (controllers == "memory")
      file = "/sys/fs/cgroup/memory" + path + "/memory.limit_in_bytes";
    else
      continue;
    std::ifstream in(file);
    std::string text;
    if (!(in >> text)) continue;
    char* end = nullptr;
    const unsigned long long value = std::strtoull(text.c_str(), &end, 10);
    if (end == text.c_str() || *end != '\0' || value == 0) continue;  // "max": no limit
    if (limit == 0 || value < limit) limit = value;
  }
  return limit;
}

bool release_freed_memory_if_large() {
#ifdef __GLIBC__
  std::uint64_t usable = physical_memory();
  if (const std::uint64_t group = cgroup_memory_limit(); group > 0 && (usable == 0 || group < usable))
    usable = group;
  if (usable == 0 || mallinfo2().fordblks <= usable / 8) return false;
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
