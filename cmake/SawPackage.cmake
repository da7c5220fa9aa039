# Installing sawrt: the CMake package (sawrtConfig.cmake, components), programs' data (example
# deployments, systemd units, the example plug-in's sources) and the .deb packages (CPack):
#   sawrt      runtime: libraries, saw-rt, saw-gateway, sawctl, deployments, systemd units
#   sawrt-dev  headers, CMake package, examples/ (build a plug-in with find_package(sawrt))
include(CMakePackageConfigHelpers)

get_property(SAW_INSTALLED_COMPONENTS GLOBAL PROPERTY SAW_INSTALLED_COMPONENTS)
file(STRINGS ${PROJECT_SOURCE_DIR}/rt/deploy/include/saw/deploy/plugin.hpp abi_line
     REGEX "plugin_abi_version = [0-9]+;")
string(REGEX REPLACE ".*= ([0-9]+);.*" "\\1" SAW_PLUGIN_ABI_VERSION "${abi_line}")

set(config_dir ${CMAKE_INSTALL_LIBDIR}/cmake/sawrt)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/sawrtConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/sawrtConfig.cmake INSTALL_DESTINATION ${config_dir})
# 0.x: a minor version may change the API and the plug-in ABI.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/sawrtConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/sawrtConfig.cmake ${PROJECT_BINARY_DIR}/sawrtConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/SawIdl.cmake
        DESTINATION ${config_dir} COMPONENT dev)

set(SAW_DATA_DIR ${CMAKE_INSTALL_DATADIR}/sawrt)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/config/ DESTINATION ${SAW_DATA_DIR}/config COMPONENT runtime
        FILES_MATCHING PATTERN "*.yaml" PATTERN "*.csv" PATTERN "README.md" PATTERN "udev" EXCLUDE)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/examples/ DESTINATION ${SAW_DATA_DIR}/examples COMPONENT dev
        PATTERN "build" EXCLUDE)
# The units name saw-rt by its installed path, known only when installing (CPack installs to /usr).
foreach(unit saw-rt@.service saw-gateway@.service)
  install(CODE "
    set(SAW_INSTALL_BINDIR \"\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_BINDIR}\")
    configure_file(\"${PROJECT_SOURCE_DIR}/config/systemd/${unit}\"
                   \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/lib/systemd/system/${unit}\" @ONLY)
    message(STATUS \"Installing: \$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/lib/systemd/system/${unit}\")"
    COMPONENT runtime)
endforeach()

set(CPACK_PACKAGE_NAME sawrt)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "sawrt developers <sawrt@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL runtime dev)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_COMPRESSION_TYPE gzip)
set(CPACK_STRIP_FILES ON)  # the debug info stays in the build tree
set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME sawrt)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SHLIBDEPS ON)  # dpkg-shlibdeps: the libraries saw-rt links
set(CPACK_DEBIAN_DEV_PACKAGE_NAME sawrt-dev)
set(dev_depends "sawrt (= ${PROJECT_VERSION}), cmake (>= 3.25), g++ | clang, libeigen3-dev, libyaml-cpp-dev")
if(SAW_WITH_DDS)
  string(APPEND dev_depends ", libfastrtps-dev, libfastcdr-dev")
endif()
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS "${dev_depends}")
set(CPACK_COMPONENT_RUNTIME_DESCRIPTION "sawrt: saw-rt, saw-gateway, sawctl, libraries, deployments, systemd units")
set(CPACK_COMPONENT_DEV_DESCRIPTION "sawrt development files: headers, CMake package, example plug-in")
include(CPack)
