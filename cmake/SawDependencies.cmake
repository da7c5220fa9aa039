# Finds the project's dependencies; tools/bootstrap.sh installs them.
find_package(Threads REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)

# Ruckig comes as the pinned PyPI sdist unpacked by tools/bootstrap.sh.
set(SAW_RUCKIG_DIR "${CMAKE_SOURCE_DIR}/.cache/ruckig-0.19.4" CACHE PATH "Ruckig source tree")
if(EXISTS "${SAW_RUCKIG_DIR}/CMakeLists.txt")
  set(BUILD_CLOUD_CLIENT OFF CACHE BOOL "" FORCE)
  set(BUILD_TESTS OFF CACHE BOOL "" FORCE)
  set(BUILD_EXAMPLES OFF CACHE BOOL "" FORCE)
  set(BUILD_PYTHON_MODULE OFF CACHE BOOL "" FORCE)
  set(BUILD_BENCHMARK OFF CACHE BOOL "" FORCE)
  set(BUILD_SHARED_LIBS OFF CACHE BOOL "" FORCE)
  add_subdirectory("${SAW_RUCKIG_DIR}" "${CMAKE_BINARY_DIR}/_deps/ruckig" EXCLUDE_FROM_ALL SYSTEM)
else()
  message(FATAL_ERROR "Ruckig not found in ${SAW_RUCKIG_DIR}: run tools/bootstrap.sh")
endif()

# Fast DDS 2.9 (Debian): nonrt/ only.
if(SAW_WITH_DDS)
  find_package(fastcdr REQUIRED)
  find_package(fastrtps REQUIRED)
endif()
include(SawSanitizers)
