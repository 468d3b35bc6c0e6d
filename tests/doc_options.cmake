# docs/options.md is what `rfd options-doc` prints (regenerate it with `make docs`), and no
# option's help types its default by hand: --help and the page show the value the option
# starts with, so a default written in the help could only disagree with it.
# Usage: cmake -DRFD=... -DPAGE=docs/options.md -P doc_options.cmake
execute_process(COMMAND ${RFD} options-doc OUTPUT_VARIABLE generated RESULT_VARIABLE code)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "rfd options-doc failed (${code})")
endif()
file(READ ${PAGE} page)
if(NOT generated STREQUAL page)
  message(FATAL_ERROR "${PAGE} differs from `rfd options-doc`: run `make docs` and commit the page")
endif()
string(REGEX MATCHALL "\\| `[^`]+`[^\n]*\\(default [0-9][^\n]*" typed "${generated}")
string(REGEX MATCHALL "[,;] default [0-9][^\n]*" typed_late "${generated}")
if(typed OR typed_late)
  message(FATAL_ERROR "help text that types its default by hand (let the option's value show it): ${typed}${typed_late}")
endif()
string(REGEX MATCHALL "\n\\| `" rows "${generated}")
list(LENGTH rows count)
if(count LESS 300)
  message(FATAL_ERROR "only ${count} options documented: is options-doc walking every command?")
endif()
message(STATUS "docs/options.md matches the program's ${count} options")
