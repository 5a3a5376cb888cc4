# Records how Eigen lays out and allocates its types under the flags msdeform is compiled with, so that
# msdeform/core/types.h can refuse, at compile time, code that includes msdeform with other settings.
#
# Eigen derives from the instruction set (-march, -mavx, ...) and from EIGEN_* defines:
#   - the alignment, hence the layout, of fixed-size types (Matrix4d: 16 bytes with SSE2, 32 with AVX);
#   - the alignment that code assumes of heap arrays, and how it allocates and frees them (malloc at
#     16 bytes; above that, or under AddressSanitizer, hand-aligned blocks freed through a pointer
#     stored before them);
#   - the size of Eigen::Index (EIGEN_DEFAULT_DENSE_INDEX_TYPE), in which dynamic matrices store their size.
# Two sides that disagree on any of these exchange objects that one of them misreads or frees wrongly:
# the symptom is a correct result and then "double free or corruption". msdeform forces no Eigen define
# on its users (that would break their other Eigen libraries); it requires the same settings instead.
set(_msd_abi_flags "")
if(MSD_NATIVE)
  set(_msd_abi_flags -march=native)
endif()
try_run(_msd_abi_run _msd_abi_compile "${PROJECT_BINARY_DIR}/eigen-abi" "${PROJECT_SOURCE_DIR}/cmake/eigen_abi.cpp"
        COMPILE_DEFINITIONS ${_msd_abi_flags}
        LINK_LIBRARIES Eigen3::Eigen
        CXX_STANDARD 17
        COMPILE_OUTPUT_VARIABLE _msd_abi_log
        RUN_OUTPUT_VARIABLE _msd_abi_out)
if(NOT _msd_abi_compile OR NOT _msd_abi_run EQUAL 0)
  message(FATAL_ERROR "msdeform: could not run the Eigen settings probe (cmake/eigen_abi.cpp):\n${_msd_abi_log}")
endif()
list(GET _msd_abi_out 0 MSD_EIGEN_MAX_STATIC_ALIGN_BYTES)
list(GET _msd_abi_out 1 MSD_EIGEN_MAX_ALIGN_BYTES)
list(GET _msd_abi_out 2 MSD_EIGEN_DEFAULT_ALIGN_BYTES)
list(GET _msd_abi_out 3 MSD_EIGEN_MALLOC_ALREADY_ALIGNED)
list(GET _msd_abi_out 4 MSD_EIGEN_VERSION)
list(GET _msd_abi_out 5 MSD_EIGEN_INDEX_BYTES)
# What a user has to match, in words for the error message: the flags that move these settings.
string(STRIP "${CMAKE_CXX_FLAGS} ${_msd_abi_flags}" MSD_ABI_FLAGS)
string(REGEX MATCHALL "(-march=|-mavx|-msse|-mfma|-mno-|-D *EIGEN_)[^ ]*" MSD_ABI_FLAGS "${MSD_ABI_FLAGS}")
list(JOIN MSD_ABI_FLAGS " " MSD_ABI_FLAGS)
if(MSD_ABI_FLAGS STREQUAL "")
  set(MSD_ABI_FLAGS "no instruction-set flag")
endif()
message(STATUS "msdeform: Eigen ${MSD_EIGEN_VERSION}, alignment ${MSD_EIGEN_MAX_STATIC_ALIGN_BYTES} (fixed-size) / "
               "${MSD_EIGEN_DEFAULT_ALIGN_BYTES} (heap) bytes with ${MSD_ABI_FLAGS}")
