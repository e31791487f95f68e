# Installs the runtime libraries, headers and programs with a CMake package config,
# so a controller project can find_package(pbppo-rt) and link pbppo::runtime (everything a
# controller uses) or its parts: pbppo::core, pbppo::policy (the blob and inference), pbppo::robot,
# pbppo::safety, pbppo::rt, pbppo::loop, pbppo::can, pbppo::dds, pbppo::transports; the robots'
# Fast DDS profile goes to share/pbppo-rt/dds_profile.xml.
include(CMakePackageConfigHelpers)

install(EXPORT pbppo-rtTargets
  NAMESPACE pbppo::
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/pbppo-rt)

configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/pbppo-rtConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/pbppo-rtConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/pbppo-rt)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/pbppo-rtConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES
  ${CMAKE_CURRENT_BINARY_DIR}/pbppo-rtConfig.cmake
  ${CMAKE_CURRENT_BINARY_DIR}/pbppo-rtConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/pbppo-rt)
