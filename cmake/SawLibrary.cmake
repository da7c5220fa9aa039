# saw_library(target COMPONENT name SOURCES ...): one of sawrt's shared libraries.
#   - in the tree: saw::<alias> (ALIAS, default: COMPONENT) and sawrt::<COMPONENT>;
#   - installed: lib/libsawrt_<COMPONENT>.so.<version>, exported as sawrt::<COMPONENT> in its own
#     export set (sawrt-<COMPONENT>-targets.cmake), so find_package(sawrt COMPONENTS x) loads
#     only x and what x needs;
#   - include/ of the calling directory is its public include path (build tree and installed).
# Shared, not static: a plug-in and saw-rt must share one copy of the core.
function(saw_library target)
  cmake_parse_arguments(L "" "COMPONENT;ALIAS" "SOURCES" ${ARGN})
  if(NOT L_ALIAS)
    set(L_ALIAS ${L_COMPONENT})
  endif()
  add_library(${target} SHARED ${L_SOURCES})
  add_library(saw::${L_ALIAS} ALIAS ${target})
  add_library(sawrt::${L_COMPONENT} ALIAS ${target})
  set_target_properties(${target} PROPERTIES
    OUTPUT_NAME sawrt_${L_COMPONENT}
    EXPORT_NAME ${L_COMPONENT}
    VERSION ${PROJECT_VERSION}
    SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR}
    LIBRARY_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/lib)
  if(EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/include)
    target_include_directories(${target} PUBLIC
      $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
      $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
    install(DIRECTORY include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT dev)
  endif()
  install(TARGETS ${target} EXPORT sawrt-${L_COMPONENT}-targets
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime NAMELINK_COMPONENT dev)
  install(EXPORT sawrt-${L_COMPONENT}-targets NAMESPACE sawrt::
    DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/sawrt COMPONENT dev)
  saw_warnings(${target})
  set_property(GLOBAL APPEND PROPERTY SAW_INSTALLED_COMPONENTS ${L_COMPONENT})
endfunction()

# saw_program(target): an installed executable, built into bin/ of the build tree.
function(saw_program target)
  set_target_properties(${target} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bin)
  install(TARGETS ${target} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
  saw_warnings(${target})
endfunction()

# saw_package(name SOURCES ... LIBS ...): a package as saw-rt loads it, a plug-in module
# (SAW_PLUGIN) in the package directory: lib/sawrt/packages of the build tree, and
# ${CMAKE_INSTALL_LIBDIR}/sawrt/packages installed. saw-rt links no package; it loads them all
# from there, in-tree ones and a lab's alike.
function(saw_package name)
  cmake_parse_arguments(P "" "" "SOURCES;LIBS" ${ARGN})
  set(target saw_package_${name})
  add_library(${target} MODULE ${P_SOURCES})
  target_link_libraries(${target} PRIVATE saw::deploy ${P_LIBS})
  set_target_properties(${target} PROPERTIES
    OUTPUT_NAME ${name} PREFIX "libsawrt-"
    LIBRARY_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/lib/sawrt/packages
    INSTALL_RPATH "$ORIGIN/../..")  # from <libdir>/sawrt/packages to <libdir>
  install(TARGETS ${target} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}/sawrt/packages COMPONENT runtime)
  saw_warnings(${target})
  set_property(GLOBAL APPEND PROPERTY SAW_PACKAGE_MODULES ${target})
  set_property(GLOBAL APPEND PROPERTY SAW_MODULE_HOSTS saw_deploy)  # what loads it builds on this
endfunction()

# saw_mapping_module(name SOURCES ... LIBS ...): a package's DDS mappings as saw-gateway and
# sawctl load them (SAW_MAPPINGS), a module in lib/sawrt/mappings of the build tree and
# ${CMAKE_INSTALL_LIBDIR}/sawrt/mappings installed. The gateway links no package: it loads every
# module of that directory at start, in-tree ones and a lab's alike.
function(saw_mapping_module name)
  cmake_parse_arguments(P "" "" "SOURCES;LIBS" ${ARGN})
  set(target saw_mappings_${name})
  add_library(${target} MODULE ${P_SOURCES})
  target_link_libraries(${target} PRIVATE saw::gateway ${P_LIBS})
  set_target_properties(${target} PROPERTIES
    OUTPUT_NAME ${name} PREFIX "libsawrt-"
    LIBRARY_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/lib/sawrt/mappings
    INSTALL_RPATH "$ORIGIN/../..")  # from <libdir>/sawrt/mappings to <libdir>
  install(TARGETS ${target} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}/sawrt/mappings COMPONENT runtime)
  saw_warnings(${target})
  set_property(GLOBAL APPEND PROPERTY SAW_MAPPING_MODULES ${target})
  set_property(GLOBAL APPEND PROPERTY SAW_MODULE_HOSTS saw_gateway)  # what loads it builds on this
endfunction()
