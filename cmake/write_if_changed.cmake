# write_if_changed(FILE TEXT): writes only when the content differs, so that a build recompiles a
# generated file only when it changed.
function(write_if_changed file text)
  set(old "")
  if(EXISTS "${file}")
    file(READ "${file}" old)
  endif()
  if(NOT "${old}" STREQUAL "${text}")
    file(WRITE "${file}" "${text}")
  endif()
endfunction()
