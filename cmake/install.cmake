# Installing cellwalk for use from other projects (docs/install.md): the layer libraries, the
# public headers and the CLI; a CMake package (find_package(cellwalk) gives cellwalk::cellwalk,
# every layer as cellwalk::<layer>, with their dependencies found again); a pkg-config file;
# and a Debian package from CPack.
get_property(cellwalk_layers GLOBAL PROPERTY CELLWALK_LAYERS)
set(cellwalk_layer_targets)
foreach(layer ${cellwalk_layers})
  list(APPEND cellwalk_layer_targets cellwalk_${layer})
endforeach()

install(TARGETS ${cellwalk_layer_targets} cellwalk_all EXPORT cellwalkTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(TARGETS cellwalk RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY include/cellwalk DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

set(cellwalk_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/cellwalk)
install(EXPORT cellwalkTargets NAMESPACE cellwalk:: DESTINATION ${cellwalk_cmake_dir})
include(CMakePackageConfigHelpers)
configure_package_config_file(cmake/cellwalkConfig.cmake.in ${CMAKE_BINARY_DIR}/cellwalkConfig.cmake
                              INSTALL_DESTINATION ${cellwalk_cmake_dir})
write_basic_package_version_file(${CMAKE_BINARY_DIR}/cellwalkConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/cellwalkConfig.cmake ${CMAKE_BINARY_DIR}/cellwalkConfigVersion.cmake
        DESTINATION ${cellwalk_cmake_dir})

# pkg-config: static libraries, so Libs lists every layer, dependents first (a layer is
# declared after the layers it uses), then what they link.
set(cellwalk_pc_libs "")
list(REVERSE cellwalk_layer_targets)
foreach(target ${cellwalk_layer_targets})
  string(APPEND cellwalk_pc_libs " -l${target}")
endforeach()
file(RELATIVE_PATH cellwalk_pc_to_prefix ${CMAKE_INSTALL_FULL_LIBDIR}/pkgconfig ${CMAKE_INSTALL_PREFIX})
configure_file(cmake/cellwalk.pc.in ${CMAKE_BINARY_DIR}/cellwalk.pc @ONLY)
install(FILES ${CMAKE_BINARY_DIR}/cellwalk.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME cellwalk)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "cellwalk developers <cellwalk@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "Interactive walkthroughs of 3D worlds larger than memory")
set(CPACK_DEBIAN_PACKAGE_SECTION graphics)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
# The CLI's shared libraries, found by dpkg-shlibdeps; the headers' packages for the library.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "libglm-dev, nlohmann-json3-dev, libmeshoptimizer-dev, libdraco-dev, libpng-dev, libjpeg-dev, libembree-dev, libtbb-dev, libglfw3-dev, libepoxy-dev, libxxhash-dev, libzstd-dev, libsqlite3-dev")
include(CPack)
