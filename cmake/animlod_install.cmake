# Installs animlod::core, its public headers and a CMake package, so that an engine can call
# find_package(animlod) (tests/consumer proves it).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

install(TARGETS animlod_core EXPORT animlodTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(DIRECTORY cpp/include/animlod DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT animlodTargets NAMESPACE animlod:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/animlod)

# The static core needs OpenMesh's libraries at link time: the config finds the same OpenMesh
# the core was built with.
set(ANIMLOD_OPENMESH_CONFIG_DIR "${OpenMesh_DIR}")
configure_package_config_file(cmake/animlodConfig.cmake.in
  "${CMAKE_CURRENT_BINARY_DIR}/animlodConfig.cmake"
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/animlod)
write_basic_package_version_file("${CMAKE_CURRENT_BINARY_DIR}/animlodConfigVersion.cmake"
  COMPATIBILITY SameMinorVersion)
install(FILES "${CMAKE_CURRENT_BINARY_DIR}/animlodConfig.cmake" "${CMAKE_CURRENT_BINARY_DIR}/animlodConfigVersion.cmake"
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/animlod)
