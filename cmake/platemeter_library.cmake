# platemeter_library(NAME PUBLIC deps... PRIVATE deps... [PCH <header>...])
# One library per folder: sources in src/ (and its subfolders, e.g. detect/src/trails/), public headers in include/platemeter/<name>/.
# Sources are globbed so that adding a file needs no edit here.
# PCH: the third-party headers most of the library's files include (Eigen, Ceres, OpenCV, ...),
# parsed once per library instead of once per file: parsing them is most of the compile time
# (scripts/build; a fresh machine's demo builds in about half the time).
# Unity build (PLATEMETER_UNITY): eight files of a library compiled as one, so the shared headers are
# parsed once per eight files (the platemeter binary: 4.1 min instead of 5.7 on 2 cores). It needs
# each library's files not to define the same names in their anonymous namespaces: shared helpers
# live in headers (core/angles.h, core/why.h, core/number_text.h, ...).
function(platemeter_library name)
  cmake_parse_arguments(ARG "" "" "PUBLIC;PRIVATE;PCH" ${ARGN})
  file(GLOB_RECURSE sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/*.cpp)
  if(NOT sources)
    message(STATUS "platemeter: ${name}/ has no sources yet; library skipped")
    return()
  endif()
  add_library(platemeter_${name} STATIC ${sources})
  add_library(platemeter::${name} ALIAS platemeter_${name})
  target_include_directories(platemeter_${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(platemeter_${name} PUBLIC ${ARG_PUBLIC} PRIVATE ${ARG_PRIVATE})
  if(ARG_PCH AND PLATEMETER_PCH)
    target_precompile_headers(platemeter_${name} PRIVATE ${ARG_PCH})
  endif()
  set_target_properties(platemeter_${name} PROPERTIES UNITY_BUILD ${PLATEMETER_UNITY} UNITY_BUILD_BATCH_SIZE ${PLATEMETER_UNITY_BATCH})
endfunction()
