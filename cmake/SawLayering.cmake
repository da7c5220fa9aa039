# The tree's dependencies run one way: the framework (rt/) knows no package. A library of rt/,
# or the saw-rt host, that links drivers/, bridge/ or nonrt/ fails the configure step, naming
# both. Packages are loaded by saw-rt at run time (saw_package), never linked into it.
function(saw_check_layering)
  set(framework saw_rt saw_deploy saw_teleop saw-rt)
  set(forbidden "^(saw::|sawrt::)?(saw_)?(bridge|can|canopen|canopen_sim|drivers_sim|drivers_falcon|falcon_kinematics|gateway|msgs|security)$")
  foreach(t IN LISTS framework)
    foreach(property LINK_LIBRARIES INTERFACE_LINK_LIBRARIES)
      get_target_property(libs ${t} ${property})
      if(NOT libs)
        continue()
      endif()
      foreach(l IN LISTS libs)
        if(l MATCHES "${forbidden}")
          message(FATAL_ERROR "layering: ${t} (rt/) links ${l}; the framework may not depend on a "
                              "package (drivers/, bridge/, nonrt/): load it as a package instead")
        endif()
      endforeach()
    endforeach()
  endforeach()
endfunction()
