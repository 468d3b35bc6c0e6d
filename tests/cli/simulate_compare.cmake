# `rfd simulate compare` end to end on Design II: a diamonds field encoded at the design's
# resolution, compared over a sweep of light directions (>= 30 dB on the axis and at 5
# degrees, every output written, byte-identical twice), the speed-versus-accuracy chart, and the
# errors a user meets: a field that is not the pattern's, a disc light, no direction at all.
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
include(${CMAKE_CURRENT_LIST_DIR}/run_rfd.cmake)

run(0 pattern field diamonds --resolution 24x20 --spread 14 --out ${OUT}/diamonds)
run(0 pattern encode ${DESIGN} ${OUT}/diamonds --out ${OUT}/diamonds.exr)
foreach(name a b)
  run(0 simulate compare ${DESIGN} ${OUT}/diamonds.exr ${OUT}/diamonds --sweep 6 --light 5,0 --out ${OUT}/${name} --json)
endforeach()
string(JSON inside GET "${last_output}" inside_fov)
string(JSON count LENGTH "${last_output}" directions)
string(JSON axis GET "${last_output}" directions 0 psnr_db)
string(JSON five GET "${last_output}" directions 6 psnr_db)
string(JSON five_angle GET "${last_output}" directions 6 display_angle_deg)
if(NOT count EQUAL 7 OR inside LESS 4 OR axis LESS 30 OR five LESS 30 OR five_angle LESS 4.99 OR five_angle GREATER 5.01)
  message(FATAL_ERROR "expected 7 directions, >= 4 inside the FOV, >= 30 dB on the axis and at 5 degrees: ${last_output}")
endif()
foreach(file light_00.png light_06_prediction.exr light_06_reference.exr light_06_error.exr directions.csv
             psnr.csv psnr.png summary.json)
  if(NOT EXISTS ${OUT}/a/${file})
    message(FATAL_ERROR "missing output ${file}")
  endif()
endforeach()
foreach(file light_03_prediction.exr light_03_reference.exr directions.csv)
  expect_same_file(${OUT}/a/${file} ${OUT}/b/${file} "comparing twice gave a different ${file}")
endforeach()

run(0 simulate compare ${DESIGN} ${OUT}/diamonds.exr ${OUT}/diamonds --sweep 3 --chart-accuracy --accuracy-rays 2,4
    --reference-rays 8 --out ${OUT}/accuracy)
if(NOT last_output MATCHES "auto \\((paraxial|exact)\\) +4 " OR NOT EXISTS ${OUT}/accuracy/accuracy.png
   OR NOT EXISTS ${OUT}/accuracy/accuracy_points.csv)
  message(FATAL_ERROR "no speed-versus-accuracy chart: ${last_output}")
endif()

run(0 pattern field letters --resolution 24x20 --out ${OUT}/letters)
run(2 simulate compare ${DESIGN} ${OUT}/diamonds.exr ${OUT}/letters --out ${OUT}/never)
if(NOT last_output MATCHES "letters: not the field the pattern .*diamonds\\.exr' was encoded from")
  message(FATAL_ERROR "unexpected message: ${last_output}")
endif()
run(2 simulate compare ${DESIGN} ${OUT}/diamonds.exr ${OUT}/diamonds --light 5,0,3 --out ${OUT}/never)
if(NOT last_output MATCHES "--light 5,0,3: compare takes point lights of white light")
  message(FATAL_ERROR "unexpected message: ${last_output}")
endif()
run(2 simulate compare ${DESIGN} ${OUT}/diamonds.exr ${OUT}/diamonds --sweep 0 --out ${OUT}/never)
if(NOT last_output MATCHES "--sweep 0 needs at least one --light")
  message(FATAL_ERROR "unexpected message: ${last_output}")
endif()
if(EXISTS ${OUT}/never)
  message(FATAL_ERROR "a refused comparison wrote its output")
endif()

# Lights in the display's frame (the default) and the field's: on a pattern encoded with a
# 10-degree tilt, display 0,0 is the display's axis, and field 0,0 is 10 degrees off it.
run(0 pattern encode ${DESIGN} ${OUT}/diamonds --tilt 10 --allow-partial --out ${OUT}/tilted.exr)
foreach(frame display field)
  run(0 simulate compare ${DESIGN} ${OUT}/tilted.exr ${OUT}/diamonds --sweep 0 --light 0,0 --frame ${frame}
      --out ${OUT}/tilted_${frame} --json)
  string(JSON angle_${frame} GET "${last_output}" directions 0 display_angle_deg)
endforeach()
if(angle_display GREATER 1e-6 OR angle_field LESS 9.999 OR angle_field GREATER 10.001)
  message(FATAL_ERROR "--light 0,0: display frame ${angle_display} deg, field frame ${angle_field} deg from the axis (expected 0 and 10)")
endif()
