#include "msdeform/core/blas_kernels.h"

#include <dlfcn.h>
#include <strings.h>
#include <sys/resource.h>
#include <unistd.h>

#include <atomic>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>

// OpenBLAS's kernel selection (DYNAMIC_ARCH builds, as Debian's) and the BLAS entry CHOLMOD calls. Weak:
// without OpenBLAS they are null, and dgemm_ resolves (or not) as it does for CHOLMOD.
extern "C" {
char* openblas_get_corename(void) __attribute__((weak));
void gotoblas_dynamic_init(void) __attribute__((weak));
void gotoblas_dynamic_quit(void) __attribute__((weak));
void dgemm_(void) __attribute__((weak));
int openblas_get_num_threads(void) __attribute__((weak));
void openblas_set_num_threads(int) __attribute__((weak));
}

namespace msd {
namespace {

// Whether the dgemm_ this process's CHOLMOD calls comes from OpenBLAS: Debian's alternatives may pair
// OpenBLAS's LAPACK (which brings openblas_get_corename) with another BLAS. Debian's OpenBLAS libblas.so.3
// forwards to libopenblas.so.0, so the test is the defining file's real path.
bool openblas_is_the_blas() {
  if (!openblas_get_corename || !dgemm_) return false;
  Dl_info info;
  if (!dladdr(reinterpret_cast<void*>(&dgemm_), &info) || !info.dli_fname) return false;
  char path[PATH_MAX];
  const char* file = realpath(info.dli_fname, path) ? path : info.dli_fname;
  return std::strstr(file, "openblas") != nullptr;
}

}  // namespace

std::string blas_kernels() {
  if (!openblas_is_the_blas()) return "";
  const char* name = openblas_get_corename();
  return name ? name : "";
}

std::string select_blas_kernels() {
  static std::mutex mutex;
  const std::lock_guard<std::mutex> lock(mutex);
#if defined(__x86_64__) || defined(__i386__)
  // blas_kernels() is "" unless OpenBLAS is the BLAS.
  if (strcasecmp(blas_kernels().c_str(), "prescott") == 0 && gotoblas_dynamic_init && gotoblas_dynamic_quit &&
      !std::getenv("OPENBLAS_CORETYPE")) {
    __builtin_cpu_init();
    const char* core = nullptr;
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") &&
        __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq") &&
        __builtin_cpu_supports("avx512vl"))
      core = "SkylakeX";
    else if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
      core = "Haswell";
    if (core) {
      setenv("OPENBLAS_CORETYPE", core, 0);
      gotoblas_dynamic_quit();
      gotoblas_dynamic_init();
      unsetenv("OPENBLAS_CORETYPE");
    }
  }
#endif
  return blas_kernels();
}

namespace {
std::atomic<bool> blas_buffer_held{false};
constexpr double kMB = 1 << 20;
// One OpenBLAS work buffer (128 MB) with malloc's and the caller's margin.
constexpr double kOneBufferMB = 160, kTwoThreadsMB = 512;
}  // namespace

BlasRoom blas_room() {
  BlasRoom room;
  rlimit limit;
  if (getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY || blas_kernels().empty())
    return room;
  unsigned long pages = 0;  // the process's address space now (the first field of statm)
  if (FILE* statm = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(statm, "%lu", &pages) != 1) pages = 0;
    std::fclose(statm);
  }
  room.limit_mb = static_cast<double>(limit.rlim_cur) / kMB;
  room.left_mb =
      room.limit_mb - static_cast<double>(pages) * static_cast<double>(sysconf(_SC_PAGESIZE)) / kMB;
  room.threads = room.left_mb >= kTwoThreadsMB ? 2 : room.left_mb >= kOneBufferMB || blas_buffer_held ? 1 : 0;
  return room;
}

void blas_call_finished() { blas_buffer_held = true; }

std::string address_space_message(const BlasRoom& room, const char* who, const std::string& what,
                                  double need_mb) {
  char numbers[200];
  std::snprintf(numbers, sizeof numbers, "%.0f MB leaves %.0f MB, and ", room.limit_mb, room.left_mb);
  char raise[160];
  std::snprintf(raise, sizeof raise,
                " needs %.0f MB: raise the limit to at least %.0f MB (this step's need; "
                "later ones may need more)",
                need_mb, room.limit_mb - room.left_mb + need_mb);
  return std::string(who) + ": the address-space limit (ulimit -v) of " + numbers + what + raise;
}

std::string no_room_for_blas_message(const BlasRoom& room, const char* who) {
  return address_space_message(
      room, who,
      "the work buffer of the factorisation's BLAS (OpenBLAS, which would wait for it "
      "forever)",
      kOneBufferMB);
}

OneBlasThread::OneBlasThread() {
  if (openblas_get_num_threads && openblas_set_num_threads && !blas_kernels().empty()) {
    saved_ = openblas_get_num_threads();
    if (saved_ > 1) openblas_set_num_threads(1);
  }
}

OneBlasThread::~OneBlasThread() {
  if (saved_ > 1) openblas_set_num_threads(saved_);
}

}  // namespace msd
