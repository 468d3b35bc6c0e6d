# Patterns for the print CLI tests, drawn by oiiotool: Design II at the test printer's
# 720 x 360 dpi (681 x 341 dots), and one of the wrong size.
file(MAKE_DIRECTORY ${OUT})
execute_process(COMMAND ${OIIOTOOL} --pattern fill:left=0.1,0.2,0.3:right=0.9,0.8,0.7 681x341 3 -d half
                        --attrib rfd:white 0.9 -o ${OUT}/design2_720x360.exr RESULT_VARIABLE code)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "oiiotool failed")
endif()
execute_process(COMMAND ${OIIOTOOL} --pattern constant:color=0.5 100x80 1 -d half -o ${OUT}/wrong_size.exr
                RESULT_VARIABLE code)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "oiiotool failed")
endif()
# The same pattern stored in 16 x 16 tiles (as `oiiotool --tile` and compositing tools
# write it), under the same file name.
file(MAKE_DIRECTORY ${OUT}/tiled)
execute_process(COMMAND ${OIIOTOOL} ${OUT}/design2_720x360.exr --tile 16 16 -o ${OUT}/tiled/design2_720x360.exr
                RESULT_VARIABLE code)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "oiiotool failed")
endif()
