#include "msdeform/core/version.h"

#include "msdeform/core/types.h"

namespace msd {

const char* version() { return MSD_VERSION_STRING; }

std::string build_info() {
#ifdef MSD_HAVE_CHOLMOD
  const std::string cholesky = "CHOLMOD";
#else
  const std::string cholesky = "Eigen SimplicialLDLT";
#endif
#ifdef __AVX2__
  const std::string isa = "AVX2";
#elif defined(__AVX__)
  const std::string isa = "AVX";
#else
  const std::string isa = "SSE2";
#endif
  return "sparse Cholesky " + cholesky + ", Eigen " + std::to_string(EIGEN_WORLD_VERSION) + "." +
         std::to_string(EIGEN_MAJOR_VERSION) + "." + std::to_string(EIGEN_MINOR_VERSION) + " (alignment " +
         std::to_string(EIGEN_MAX_STATIC_ALIGN_BYTES) + " bytes fixed-size, " + std::to_string(EIGEN_DEFAULT_ALIGN_BYTES) +
         " heap), compiled for " + isa + " (" + MSD_ABI_FLAGS + ")";
}

}  // namespace msd
