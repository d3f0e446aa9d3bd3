# Accuracy against cost (bench/accuracy.cpp, issue 6): included from bench/CMakeLists.txt with
# include(${CMAKE_CURRENT_SOURCE_DIR}/accuracy.cmake OPTIONAL). Never run by ctest.
add_executable(bench_accuracy ${CMAKE_CURRENT_LIST_DIR}/accuracy.cpp)
target_link_libraries(bench_accuracy PRIVATE hopper::engine hopper_options)
