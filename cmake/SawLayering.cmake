# The tree's dependencies run one way, checked by rule for every target the project defines, over
# everything it links, directly or not (LINK_LIBRARIES and INTERFACE_LINK_LIBRARIES, aliases
# resolved). A new package or target is covered without editing this file.
#
# 1. Folders: a target's layer is the top folder of its source directory.
#      rt/      the framework: links rt/ only
#      drivers/ devices:       rt/ and drivers/
#      bridge/  shared memory: rt/ and bridge/
#      nonrt/   DDS side:      rt/, bridge/ and nonrt/
#      tools/, tests/, examples/ may link anything; a third party's (IMPORTED, or added as SYSTEM)
#      and the root's own (build support from cmake/: the sanitizers' shim) are outside the rules.
# 2. Packages are loaded, not linked by the framework: a package folder is the source directory
#    of a package module (saw_package) or a mapping module (saw_mapping_module). The framework is
#    every target in no package folder (rt/'s core, saw-rt) and every target in a host folder,
#    the folder of the library a kind of module is built against (SAW_MODULE_HOSTS: saw_deploy,
#    saw_gateway), even where a module sits too (the gateway's own `gateway:` package). The
#    framework links no package's target but its own folder's and a whole layer's (bridge/). A
#    package may build on another's library (the simulated Falcon on the Falcon's kinematics; a
#    package's DDS side on the package). So saw-rt links no device, the gateway no component.
# Broken, the configure step fails naming the target, what it links, and the chain to it.

# The targets defined in DIR and below.
function(_saw_targets_below dir out)
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  get_property(subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(d IN LISTS subdirs)
    _saw_targets_below(${d} below)
    list(APPEND targets ${below})
  endforeach()
  set(${out} ${targets} PARENT_SCOPE)
endfunction()

# The project's own target NAME names (aliases resolved), or "" for anything else.
function(_saw_own_target name out)
  set(${out} "" PARENT_SCOPE)
  string(REGEX REPLACE "^\\$<LINK_ONLY:(.*)>$" "\\1" name "${name}")
  if(NOT TARGET "${name}")
    return()
  endif()
  get_target_property(aliased "${name}" ALIASED_TARGET)
  if(aliased)
    set(name ${aliased})
  endif()
  get_target_property(imported "${name}" IMPORTED)
  get_target_property(third_party "${name}" SYSTEM)  # add_subdirectory(... SYSTEM): Ruckig's sdist
  if(imported OR third_party)
    return()
  endif()
  set(${out} ${name} PARENT_SCOPE)
endfunction()

# A target's source folder, relative to the project's source directory.
function(_saw_folder target out)
  get_target_property(dir ${target} SOURCE_DIR)
  file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${dir})
  set(${out} "${rel}" PARENT_SCOPE)
endfunction()

# Whether FOLDER is PARENT or below it.
function(_saw_within folder parent out)
  if(folder STREQUAL parent OR folder MATCHES "^${parent}/")
    set(${out} TRUE PARENT_SCOPE)
  else()
    set(${out} FALSE PARENT_SCOPE)
  endif()
endfunction()

# The package folders the module kind PROPERTY (a global list of module targets) names.
function(_saw_module_folders property out)
  get_property(modules GLOBAL PROPERTY ${property})
  set(folders "")
  foreach(m IN LISTS modules)
    _saw_folder(${m} f)
    list(APPEND folders ${f})
  endforeach()
  list(REMOVE_DUPLICATES folders)
  set(${out} ${folders} PARENT_SCOPE)
endfunction()

function(saw_check_layering)
  set(allowed_rt rt)
  set(allowed_drivers rt drivers)
  set(allowed_bridge rt bridge)
  set(allowed_nonrt rt bridge nonrt)
  set(free tools tests examples)
  _saw_module_folders(SAW_PACKAGE_MODULES packages)
  _saw_module_folders(SAW_MAPPING_MODULES mappings)
  set(package_folders ${packages} ${mappings})
  list(REMOVE_DUPLICATES package_folders)
  get_property(hosts GLOBAL PROPERTY SAW_MODULE_HOSTS)
  list(REMOVE_DUPLICATES hosts)
  set(host_folders "")
  foreach(h IN LISTS hosts)
    if(TARGET ${h})
      _saw_folder(${h} f)
      list(APPEND host_folders ${f})
    endif()
  endforeach()
  _saw_targets_below(${PROJECT_SOURCE_DIR} targets)
  set(checked 0)
  foreach(t IN LISTS targets)
    get_target_property(type ${t} TYPE)
    _saw_own_target(${t} own)
    if(type STREQUAL "UTILITY" OR NOT own)
      continue()  # custom targets link nothing; a third party's are not ours to lay out
    endif()
    _saw_folder(${t} folder)
    string(REGEX REPLACE "/.*" "" layer "${folder}")
    if(layer IN_LIST free OR folder STREQUAL "")
      continue()  # the root's own: build support the cmake/ modules add (the sanitizers' shim)
    endif()
    if(NOT DEFINED allowed_${layer})
      message(FATAL_ERROR "layering: ${t} is in ${folder}/, which no layer names: put it under rt/, drivers/, "
                          "bridge/, nonrt/, tools/, tests/ or examples/ (cmake/SawLayering.cmake)")
    endif()
    # The package folder T is in ("" for none), and whether T is the framework's.
    set(own_package "")
    foreach(p IN LISTS package_folders)
      _saw_within(${folder} ${p} in)
      if(in)
        set(own_package ${p})
      endif()
    endforeach()
    set(framework FALSE)
    if(NOT own_package OR folder IN_LIST host_folders)
      set(framework TRUE)
    endif()
    # Breadth-first over what T links; `via_<target>` keeps the chain for the message.
    set(queue ${t})
    set(seen ${t})
    set(via_${t} ${t})
    while(queue)
      list(POP_FRONT queue current)
      set(links "")
      foreach(property LINK_LIBRARIES INTERFACE_LINK_LIBRARIES)
        get_target_property(l ${current} ${property})
        if(l)
          list(APPEND links ${l})
        endif()
      endforeach()
      foreach(raw IN LISTS links)
        _saw_own_target("${raw}" d)
        if(NOT d OR d IN_LIST seen)
          continue()
        endif()
        list(APPEND seen ${d})
        list(APPEND queue ${d})
        set(via_${d} ${via_${current}} ${d})
        string(REPLACE ";" " -> " chain "${via_${d}}")
        _saw_folder(${d} dfolder)
        string(REGEX REPLACE "/.*" "" dlayer "${dfolder}")
        if(dfolder STREQUAL "")
          continue()  # build support, linked into every layer
        endif()
        if(NOT dlayer IN_LIST allowed_${layer})
          list(JOIN allowed_${layer} "/, " may)
          message(FATAL_ERROR "layering: ${t} (${folder}/) links ${d} (${dfolder}/): ${layer}/ may link only "
                              "${may}/ (${chain})")
        endif()
        foreach(p IN LISTS package_folders)
          _saw_within(${dfolder} ${p} in)
          if(in AND framework AND NOT p STREQUAL own_package AND NOT p STREQUAL dlayer)
            message(FATAL_ERROR "layering: ${t} (${folder}/) links ${d} of the package in ${p}/: the "
                                "framework loads a package, it does not link it (${chain})")
          endif()
        endforeach()
      endforeach()
    endwhile()
    math(EXPR checked "${checked} + 1")
  endforeach()
  set_property(GLOBAL PROPERTY SAW_LAYERING_CHECKED ${checked})
endfunction()
