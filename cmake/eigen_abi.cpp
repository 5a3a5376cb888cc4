// Prints the Eigen settings that fix the binary interface of msdeform's headers, as this compiler and
// these flags see them (cmake/EigenAbi.cmake runs it at configure time and records them in config.h).
#include <Eigen/Core>
#include <cstdio>

int main() {
  std::printf("%d;%d;%d;%d;%d.%d.%d;%d", EIGEN_MAX_STATIC_ALIGN_BYTES, EIGEN_MAX_ALIGN_BYTES, EIGEN_DEFAULT_ALIGN_BYTES,
              EIGEN_MALLOC_ALREADY_ALIGNED, EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION,
              static_cast<int>(sizeof(Eigen::Index)));
  return 0;
}
