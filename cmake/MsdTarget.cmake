# msd_add_module(NAME SOURCES ... [PUBLIC deps] [PRIVATE deps] [INTERNAL])
# One library per top-level module: target msd_NAME, alias msd::NAME, exported (installed) as
# msdeform::NAME with its headers under include/msdeform/NAME/. Inside the build tree the same spelling
# resolves through ${MSD_INCLUDE_DIR}/msdeform/NAME, a link to the module's folder, so code, tests and
# consumers all write #include "msdeform/NAME/header.h".
# INTERNAL: not installed (the comparison runner under apps/, which the command line and tests share).
function(msd_add_module name)
  cmake_parse_arguments(ARG "INTERNAL" "" "SOURCES;PUBLIC;PRIVATE" ${ARGN})
  set(type ${MSD_LIBRARY_TYPE})
  if(ARG_INTERNAL)
    set(type STATIC)  # linked into the programs, so there is nothing to install
  endif()
  add_library(msd_${name} ${type} ${ARG_SOURCES})
  add_library(msd::${name} ALIAS msd_${name})
  set_target_properties(msd_${name} PROPERTIES OUTPUT_NAME msdeform_${name} EXPORT_NAME ${name}
                                               VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR})
  target_include_directories(msd_${name} PUBLIC $<BUILD_INTERFACE:${MSD_INCLUDE_DIR}>
                                                $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(msd_${name} PUBLIC ${ARG_PUBLIC} PRIVATE ${ARG_PRIVATE})
  target_compile_features(msd_${name} PUBLIC cxx_std_17)
  msd_set_warnings(msd_${name})
  if(ARG_INTERNAL)
    target_include_directories(msd_${name} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>)
    return()
  endif()
  file(CREATE_LINK "${CMAKE_CURRENT_SOURCE_DIR}" "${MSD_INCLUDE_DIR}/msdeform/${name}" SYMBOLIC)
  set_property(GLOBAL APPEND PROPERTY MSD_MODULES ${name})
  if(MSD_INSTALL)
    install(TARGETS msd_${name} EXPORT msdeformTargets
            LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime
            ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT development)
    install(DIRECTORY "${CMAKE_CURRENT_SOURCE_DIR}/" DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}/msdeform/${name}"
            COMPONENT development FILES_MATCHING PATTERN "*.h")
  endif()
endfunction()

function(msd_set_warnings target)
  # g++ 12 reports false "maybe uninitialized" positives inside Eigen's AVX-512 intrinsics.
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wno-maybe-uninitialized)
endfunction()
