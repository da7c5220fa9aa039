# ASan builds: Fast DDS 2.9's own new-delete-type-mismatch (in ~RTPSWriter and ~RTPSReader) is
# let through by those destructors' names and nothing else; tests/sanitizers/fastdds_sized_delete.cpp says why.
# The replacement operator delete must be in the executable (a library would come after ASan's
# runtime), so every executable that links Fast DDS gets the object file on its link line.
if(CMAKE_CXX_FLAGS MATCHES "sanitize=[a-z,-]*address")
  add_library(saw_fastdds_asan_objects OBJECT ${CMAKE_SOURCE_DIR}/tests/sanitizers/fastdds_sized_delete.cpp)
  add_library(saw_fastdds_asan INTERFACE)
  target_link_libraries(saw_fastdds_asan INTERFACE $<TARGET_OBJECTS:saw_fastdds_asan_objects> ${CMAKE_DL_LIBS})
  set_property(TARGET fastrtps APPEND PROPERTY INTERFACE_LINK_LIBRARIES saw_fastdds_asan)
endif()
