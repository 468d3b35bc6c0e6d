# A view set end to end: `rfd capture render` on a scene with five cameras writes view_00 ...
# view_04 and views.txt (count + one line per view: folder, direction, 9 rotation numbers),
# and `rfd pattern encode-angular` encodes it for Design IV.
file(REMOVE_RECURSE ${OUT})
execute_process(COMMAND ${RFD} --quiet capture render ${SCENE} --lights 30 --resolution 14x14 --samples-per-pixel 1 --out ${OUT}/views
                RESULT_VARIABLE code ERROR_VARIABLE stderr OUTPUT_QUIET)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "capture render failed (${code}): ${stderr}")
endif()
file(STRINGS ${OUT}/views/views.txt lines REGEX "^[^#]")
list(LENGTH lines count)
if(NOT count EQUAL 6)
  message(FATAL_ERROR "views.txt has ${count} non-comment lines, expected 6: ${lines}")
endif()
list(GET lines 2 right)
string(REPLACE " " ";" fields "${right}")
list(LENGTH fields nfields)
list(GET fields 0 name)
list(GET fields 1 x)
if(NOT name STREQUAL "view_01" OR NOT nfields EQUAL 13 OR NOT x MATCHES "^0\\.20")
  message(FATAL_ERROR "views.txt line for the right camera: '${right}'")
endif()
execute_process(COMMAND ${RFD} --quiet pattern encode-angular ${DESIGN} ${OUT}/views --dpi 50 --table 17 --out ${OUT}/pattern.exr
                RESULT_VARIABLE code OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr)
if(NOT code EQUAL 0 OR NOT EXISTS ${OUT}/pattern.exr)
  message(FATAL_ERROR "encode-angular failed (${code}): ${stderr}")
endif()
string(FIND "${stdout}" "macro grid 7 x 7" found)
if(found EQUAL -1)
  message(FATAL_ERROR "unexpected summary: ${stdout}")
endif()

# --region X,Y,W,H reads every view's images through the window: the whole 14 x 14 image is
# the same pattern as none; the old fraction syntax says where it went (--coverage).
execute_process(COMMAND ${RFD} --quiet pattern encode-angular ${DESIGN} ${OUT}/views --dpi 50 --table 17
                        --region 0,0,14,14 --out ${OUT}/pattern_window.exr
                RESULT_VARIABLE code ERROR_VARIABLE stderr OUTPUT_QUIET)
file(SHA256 ${OUT}/pattern.exr whole)
file(SHA256 ${OUT}/pattern_window.exr windowed)
if(NOT code EQUAL 0 OR NOT whole STREQUAL windowed)
  message(FATAL_ERROR "--region over the whole image changed the pattern (${code}): ${stderr}")
endif()
execute_process(COMMAND ${RFD} --quiet pattern encode-angular ${DESIGN} ${OUT}/views --dpi 50 --table 17
                        --region 2,2,10,10 --coverage 0.9 --out ${OUT}/pattern_part.exr
                RESULT_VARIABLE code ERROR_VARIABLE stderr OUTPUT_QUIET)
if(NOT code EQUAL 0 OR NOT EXISTS ${OUT}/pattern_part.exr)
  message(FATAL_ERROR "--region 2,2,10,10 --coverage 0.9 failed (${code}): ${stderr}")
endif()
execute_process(COMMAND ${RFD} --quiet pattern encode-angular ${DESIGN} ${OUT}/views --region 0.5 --out ${OUT}/never.exr
                RESULT_VARIABLE code ERROR_VARIABLE stderr OUTPUT_QUIET)
if(NOT code EQUAL 2 OR NOT stderr MATCHES "--coverage" OR EXISTS ${OUT}/never.exr)
  message(FATAL_ERROR "--region 0.5: expected exit 2 naming --coverage (${code}): ${stderr}")
endif()
