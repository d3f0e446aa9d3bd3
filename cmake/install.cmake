# `cmake --install BUILD --prefix P` installs
#   P/bin/campaign                       the executable
#   P/share/hopper/analysis/*.py         the scripts campaign plot/export run (found from bin/)
#   P/share/hopper/campaigns/            the shipped sweep files
#   P/include/hopper/<layer>/*.hpp       the layers' headers
#   P/lib/libhopper_<layer>.a            the layers, as CMake targets hopper::core,
#                                        hopper::engine, hopper::config, hopper::stats,
#                                        hopper::store, hopper::campaign, hopper::analysis
#   P/lib/cmake/hopper/hopperConfig.cmake, hopperConfigVersion.cmake, hopperTargets.cmake
# so that another project says `find_package(hopper 0.3 REQUIRED)` and
# `target_link_libraries(app PRIVATE hopper::engine)` (tests/install checks it).
include(CMakePackageConfigHelpers)

set(hopper_layers core engine config stats store campaign analysis)
foreach(layer ${hopper_layers})
  set_target_properties(hopper_${layer} PROPERTIES EXPORT_NAME ${layer})
endforeach()
# The shared warning flags travel with the static libraries as a link-only dependency.
set_target_properties(hopper_options PROPERTIES EXPORT_NAME options)

set(hopper_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/hopper)
install(TARGETS hopper_options hopper_core hopper_engine hopper_config hopper_stats hopper_store
                hopper_campaign hopper_analysis
        EXPORT hopperTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/hopper DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT hopperTargets NAMESPACE hopper:: DESTINATION ${hopper_cmake_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/hopperConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/hopperConfig.cmake
                              INSTALL_DESTINATION ${hopper_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/hopperConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/hopperConfig.cmake ${PROJECT_BINARY_DIR}/hopperConfigVersion.cmake
        DESTINATION ${hopper_cmake_dir})

if(TARGET campaign)
  install(TARGETS campaign RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()
install(DIRECTORY ${PROJECT_SOURCE_DIR}/analysis/ DESTINATION ${CMAKE_INSTALL_DATADIR}/hopper/analysis
        FILES_MATCHING PATTERN "*.py" PATTERN "__pycache__" EXCLUDE PATTERN "figures" EXCLUDE)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/campaigns/ DESTINATION ${CMAKE_INSTALL_DATADIR}/hopper/campaigns)
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE ${PROJECT_SOURCE_DIR}/CITATION.cff
        DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/hopper)
