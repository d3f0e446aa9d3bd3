# Issue 28: recorded sweep texts are parsed back in one place only, the legacy path of
# src/campaign/stored_scenes.cpp (stores older than typed parameters, and the campaign target that
# no journal record holds typed). Before the scene schema, four files each had their own "newest
# run first" loop over config::parse_sweep. Fails when a file outside config/ and that one calls
# parse_sweep (load_sweep, which reads a sweep file from disk, is not a recorded text).
# usage: cmake -DSRC=<source dir> -P one_legacy_path.cmake
file(GLOB_RECURSE sources "${SRC}/src/*.cpp" "${SRC}/src/*.hpp" "${SRC}/include/*.hpp")
set(offenders "")
foreach(f IN LISTS sources)
  file(RELATIVE_PATH rel "${SRC}" "${f}")
  if(rel MATCHES "^src/config/" OR rel MATCHES "^include/hopper/config/" OR
     rel STREQUAL "src/campaign/stored_scenes.cpp")
    continue()
  endif()
  file(STRINGS "${f}" hits REGEX "parse_sweep[ ]*\\(")
  if(hits)
    list(APPEND offenders "${rel}")
  endif()
endforeach()
if(offenders)
  message(FATAL_ERROR "recorded sweep texts parsed outside the legacy path (src/campaign/stored_scenes.cpp): ${offenders}")
endif()
file(STRINGS "${SRC}/src/campaign/stored_scenes.cpp" legacy REGEX "parse_sweep[ ]*\\(")
if(NOT legacy)
  message(FATAL_ERROR "src/campaign/stored_scenes.cpp no longer parses recorded sweep texts: update this test")
endif()
message(STATUS "one legacy path: only src/campaign/stored_scenes.cpp parses recorded sweep texts")
