# Install rules and the CMake package: find_package(msdeform) gives msdeform::core, ::decomposition,
# ::detail, ::deformation, ::reconstruction, ::analysis and the umbrella msdeform::msdeform.
include(CMakePackageConfigHelpers)
set(MSD_CMAKE_DIR "${CMAKE_INSTALL_LIBDIR}/cmake/msdeform")

install(TARGETS msd_msdeform EXPORT msdeformTargets)
if(NOT MSD_SHARED)
  # Static libraries carry their private dependencies to the user's link line.
  install(TARGETS msd_opensubdiv msd_stb EXPORT msdeformTargets)
  if(TARGET msd_cholmod)
    install(TARGETS msd_cholmod msd_lapack EXPORT msdeformTargets)
  endif()
endif()
install(EXPORT msdeformTargets NAMESPACE msdeform:: DESTINATION "${MSD_CMAKE_DIR}" COMPONENT development)
install(FILES "${MSD_INCLUDE_DIR}/msdeform/version.h" "${MSD_INCLUDE_DIR}/msdeform/config.h" DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}/msdeform"
        COMPONENT development)

configure_package_config_file(cmake/msdeformConfig.cmake.in "${PROJECT_BINARY_DIR}/msdeformConfig.cmake"
                              INSTALL_DESTINATION "${MSD_CMAKE_DIR}")
# 0.x: a minor release may change the API, so only the same major.minor is compatible.
write_basic_package_version_file("${PROJECT_BINARY_DIR}/msdeformConfigVersion.cmake"
                                 COMPATIBILITY SameMinorVersion)
install(FILES "${PROJECT_BINARY_DIR}/msdeformConfig.cmake" "${PROJECT_BINARY_DIR}/msdeformConfigVersion.cmake"
        DESTINATION "${MSD_CMAKE_DIR}" COMPONENT development)
install(FILES LICENSE README.md CHANGELOG.md DESTINATION "${CMAKE_INSTALL_DATADIR}/doc/msdeform"
        COMPONENT runtime)
