# saw_warnings(target): the project's warning flags, errors when SAW_WERROR is on.
function(saw_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
                                           -Wno-sign-conversion)
  if(SAW_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
