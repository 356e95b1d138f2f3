# Writes OUT, a .cpp defining `const char* const NAME` in eds::report for each NAME=FILE of ASSETS (a
# ;-list), each holding the file's text as a raw string literal: the report's style sheet and scripts
# are compiled in, so that `eds report` needs no file at run time.
set(text "// Generated from src/report/assets/ by cmake/embed_assets.cmake; do not edit.\n#include \"report/assets.hpp\"\n\nnamespace eds::report {\n")
foreach(pair IN LISTS ASSETS)
  string(REPLACE "=" ";" parts "${pair}")
  list(GET parts 0 name)
  list(GET parts 1 file)
  file(READ "${file}" body)
  string(FIND "${body}" ")EDSASSET\"" clash)
  if(NOT clash EQUAL -1)
    message(FATAL_ERROR "${file} contains the raw-string delimiter )EDSASSET\"")
  endif()
  string(APPEND text "const char* const ${name} = R\"EDSASSET(${body})EDSASSET\";\n")
endforeach()
string(APPEND text "\n}  // namespace eds::report\n")
include(${CMAKE_CURRENT_LIST_DIR}/write_if_changed.cmake)
write_if_changed("${OUT}" "${text}")
