# Writes OUT (a .cpp defining eds::versionString) from VERSION and the source tree's git commit; the
# file is rewritten only when its text changes, so that a build recompiles it only then.
execute_process(COMMAND git -C "${SRC}" describe --always --dirty --abbrev=12
                OUTPUT_VARIABLE commit OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE rc)
if(NOT rc EQUAL 0 OR commit STREQUAL "")
  set(commit "unknown")
endif()
set(text "#include \"core/version.hpp\"\nstd::string eds::versionString() { return \"${VERSION} (commit ${commit})\"; }\n")
include(${CMAKE_CURRENT_LIST_DIR}/write_if_changed.cmake)
write_if_changed("${OUT}" "${text}")
