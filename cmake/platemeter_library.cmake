# platemeter_library(NAME PUBLIC deps... PRIVATE deps... [PCH <header>...])
# One library per folder: sources in src/, public headers in include/platemeter/<name>/.
# Sources are globbed so that adding a file needs no edit here.
# PCH: the third-party headers most of the library's files include (Eigen, Ceres, OpenCV, ...),
# parsed once per library instead of once per file: parsing them is most of the compile time
# (scripts/build; a fresh machine's demo builds in about half the time).
function(platemeter_library name)
  cmake_parse_arguments(ARG "" "" "PUBLIC;PRIVATE;PCH" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/*.cpp)
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
endfunction()
