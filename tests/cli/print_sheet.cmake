# rfd print sheet end to end: a front TIFF and a mirrored back PDF appear, nothing else is
# left in the output folder, a rerun gives identical bytes, and so does the same pattern
# stored in tiles (TILED).
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT} ${OUT}/tiled)
foreach(name front.tif front_again.tif back.pdf)
  set(extra "")
  if(name STREQUAL "back.pdf")
    set(extra --mirror --sheets 2)
  endif()
  execute_process(COMMAND ${RFD} -q print sheet ${DESIGN} ${PATTERN} --printer ${PRINTER} --brightness 1.1
                          ${extra} --out ${OUT}/${name}
                  RESULT_VARIABLE code OUTPUT_VARIABLE output ERROR_VARIABLE errors)
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "print sheet ${name} failed (${code}): ${output} ${errors}")
  endif()
endforeach()
file(GLOB left LIST_DIRECTORIES false RELATIVE ${OUT} ${OUT}/*)
list(SORT left)
if(NOT left STREQUAL "back.pdf;front.tif;front_again.tif")
  message(FATAL_ERROR "unexpected files: ${left}")
endif()
file(SHA256 ${OUT}/front.tif a)
file(SHA256 ${OUT}/front_again.tif b)
if(NOT a STREQUAL b)
  message(FATAL_ERROR "reruns differ")
endif()
execute_process(COMMAND ${RFD} -q print sheet ${DESIGN} ${TILED} --printer ${PRINTER} --brightness 1.1
                        --out ${OUT}/tiled/front.tif
                RESULT_VARIABLE code OUTPUT_VARIABLE output ERROR_VARIABLE errors)
file(SHA256 ${OUT}/tiled/front.tif c)
if(NOT code EQUAL 0 OR NOT a STREQUAL c)
  message(FATAL_ERROR "the tiled pattern's sheet differs (exit ${code}): ${output} ${errors}")
endif()
