# `make install` and a package config so that find_package(penumbra) works.
include(CMakePackageConfigHelpers)
install(TARGETS penumbra penumbra_core penumbra_flatland penumbra_spaceland penumbra_analysis penumbra_cli
  EXPORT penumbraTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY include/penumbra DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT penumbraTargets NAMESPACE penumbra::
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/penumbra)
configure_package_config_file(cmake/penumbraConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/penumbraConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/penumbra)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/penumbraConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/penumbraConfig.cmake
  ${CMAKE_CURRENT_BINARY_DIR}/penumbraConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/penumbra)
