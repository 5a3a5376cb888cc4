# Locates msdeform's Debian packages. Order matters: CGAL puts its own FindEigen3/FindOpenMesh modules
# on the module path, so every other package is found first and in CONFIG mode (design.md §5).

find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(OpenMesh REQUIRED CONFIG)
find_package(TBB REQUIRED CONFIG)
find_package(embree 3 REQUIRED CONFIG)
if(MSD_BUILD_APPS)
  find_package(CLI11 REQUIRED CONFIG)
endif()
if(MSD_BUILD_TESTS)
  find_package(Catch2 2 REQUIRED CONFIG)
endif()

# SuiteSparse 5.12 ships neither a CMake config nor a .pc file.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(CHOLMOD_LIBRARY cholmod)
find_library(SUITESPARSE_CONFIG_LIBRARY suitesparseconfig)
if(CHOLMOD_INCLUDE_DIR AND CHOLMOD_LIBRARY AND SUITESPARSE_CONFIG_LIBRARY)
  add_library(msd_cholmod INTERFACE)
  target_include_directories(msd_cholmod SYSTEM INTERFACE "${CHOLMOD_INCLUDE_DIR}")
  target_link_libraries(msd_cholmod INTERFACE "${CHOLMOD_LIBRARY}" "${SUITESPARSE_CONFIG_LIBRARY}")
  # The BLAS and LAPACK CHOLMOD calls, for the supernodal factorisation's own calls (core/).
  find_library(MSD_BLAS_LIBRARY blas)
  find_library(MSD_LAPACK_LIBRARY lapack)
  if(NOT MSD_BLAS_LIBRARY OR NOT MSD_LAPACK_LIBRARY)
    message(FATAL_ERROR "BLAS or LAPACK (libopenblas-dev) not found: run scripts/setup.sh")
  endif()
  add_library(msd_lapack INTERFACE)
  target_link_libraries(msd_lapack INTERFACE "${MSD_LAPACK_LIBRARY}" "${MSD_BLAS_LIBRARY}")
  set(MSD_HAVE_CHOLMOD ON)
  message(STATUS "msdeform: sparse Cholesky = CHOLMOD (${CHOLMOD_LIBRARY})")
else()
  set(MSD_HAVE_CHOLMOD OFF)
  message(STATUS "msdeform: CHOLMOD not found, sparse Cholesky = Eigen SimplicialLDLT (slow on large meshes)")
endif()

# Debian's OpenSubdivConfig.cmake names a static library that is not shipped: locate Far by hand.
find_path(OPENSUBDIV_INCLUDE_DIR opensubdiv/far/topologyRefiner.h)
find_library(OPENSUBDIV_CPU_LIBRARY osdCPU)
if(NOT OPENSUBDIV_INCLUDE_DIR OR NOT OPENSUBDIV_CPU_LIBRARY)
  message(FATAL_ERROR "OpenSubdiv (libosd-dev) not found: run scripts/setup.sh")
endif()
add_library(msd_opensubdiv INTERFACE)
target_include_directories(msd_opensubdiv SYSTEM INTERFACE "${OPENSUBDIV_INCLUDE_DIR}")
target_link_libraries(msd_opensubdiv INTERFACE "${OPENSUBDIV_CPU_LIBRARY}")

# CGAL last (see the top of this file). Only analysis/ uses it, in one translation unit.
find_package(CGAL REQUIRED)

# stb_image_write for PNG output (Debian libstb-dev ships headers under stb/ and a compiled libstb).
find_path(STB_INCLUDE_DIR stb/stb_image_write.h)
find_library(STB_LIBRARY stb)
if(NOT STB_INCLUDE_DIR OR NOT STB_LIBRARY)
  message(FATAL_ERROR "stb (libstb-dev) not found: run scripts/setup.sh")
endif()
add_library(msd_stb INTERFACE)
target_include_directories(msd_stb SYSTEM INTERFACE "${STB_INCLUDE_DIR}")
target_link_libraries(msd_stb INTERFACE "${STB_LIBRARY}")
