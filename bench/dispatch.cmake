# Dispatch capacity of the campaign master (bench/dispatch.cpp): included from
# bench/CMakeLists.txt with include(${CMAKE_CURRENT_SOURCE_DIR}/dispatch.cmake OPTIONAL).
if(TARGET hopper::campaign)
  add_executable(bench_dispatch ${CMAKE_CURRENT_LIST_DIR}/dispatch.cpp)
  target_link_libraries(bench_dispatch PRIVATE hopper::campaign hopper_options)
endif()
