# msd_add_module(NAME SOURCES ... [PUBLIC deps] [PRIVATE deps]) — one library per top-level module,
# exported as msd::NAME, with headers included as "NAME/header.h".
function(msd_add_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC;PRIVATE" ${ARGN})
  add_library(msd_${name} ${ARG_SOURCES})
  add_library(msd::${name} ALIAS msd_${name})
  target_include_directories(msd_${name} PUBLIC "${PROJECT_SOURCE_DIR}")
  target_link_libraries(msd_${name} PUBLIC ${ARG_PUBLIC} PRIVATE ${ARG_PRIVATE})
  msd_set_warnings(msd_${name})
endfunction()

function(msd_set_warnings target)
  # g++ 12 reports false "maybe uninitialized" positives inside Eigen's AVX-512 intrinsics.
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wno-maybe-uninitialized)
endfunction()
