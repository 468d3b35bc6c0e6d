# `rfd capture calibrate` finding the spheres by itself in a capture of scenes/dome.toml (a
# chrome and a black ball in the corners, 7 degrees off the pinhole's axis), rendered at
# 600x400 under 12 lights and saved as JPEG at quality 85: both spheres found, the black one
# giving the directions, the lights within the bounds scripts/sphere_study.sh measures at
# this size (mean 0.33, worst 0.86 degrees); the spheres written by --save-overrides and read
# back by --overrides give the same light file; --drop leaves a photograph out.
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT}/jpeg)
execute_process(COMMAND ${RFD} --quiet capture render ${SCENE} --lights 12 --resolution 600x400 --out ${OUT}/render
                RESULT_VARIABLE code ERROR_VARIABLE stderr OUTPUT_QUIET)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "rfd capture render failed (${code}): ${stderr}")
endif()
file(GLOB renders ${OUT}/render/field_*.exr)
set(photos "")
foreach(exr ${renders})
  get_filename_component(name ${exr} NAME_WE)
  execute_process(COMMAND ${OIIOTOOL} ${exr} --colorconvert linear sRGB -d uint8 --compression jpeg:85
                          -o ${OUT}/jpeg/${name}.jpg RESULT_VARIABLE code)
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "oiiotool failed on ${exr}")
  endif()
  list(APPEND photos ${OUT}/jpeg/${name}.jpg)
endforeach()

# f = 200 px / tan(9.7 deg / 2): the scene's camera at this size.
set(focal 2357.09)
execute_process(COMMAND ${RFD} capture calibrate ${photos} --focal-length-px ${focal} --out ${OUT}/lights.lp
                        --compare ${OUT}/render/field.lp --save-overrides ${OUT}/overrides.toml --json
                RESULT_VARIABLE code OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "rfd capture calibrate failed (${code}): ${stderr}")
endif()
string(JSON spheres LENGTH "${stdout}" spheres)
string(JSON mean GET "${stdout}" error_deg mean)
string(JSON worst GET "${stdout}" error_deg worst)
if(NOT spheres EQUAL 2 OR mean GREATER 0.5 OR worst GREATER 1.2)
  message(FATAL_ERROR "expected 2 spheres, lights within 0.5 deg on average and 1.2 at worst; got ${spheres} "
                      "spheres, mean ${mean}, worst ${worst}")
endif()
# The black ball, the primary, within half a pixel of where the camera sees it (centre
# 538.57, 338.37, radius 28.44 px); the chrome ball's outline, a step of its reflectance only
# against the table it mirrors (docs/methods.md), within two (centre 61.43, 61.63).
foreach(i 0 1)
  string(JSON x GET "${stdout}" spheres ${i} circle_px 0)
  string(JSON y GET "${stdout}" spheres ${i} circle_px 1)
  string(JSON r GET "${stdout}" spheres ${i} circle_px 2)
  string(JSON primary GET "${stdout}" spheres ${i} primary)
  if(x GREATER 300)
    set(bounds 538.07 539.07 337.87 338.87 27.94 28.94 ON)
  else()
    set(bounds 59.43 63.43 59.63 63.63 26.44 30.44 OFF)
  endif()
  list(GET bounds 0 x0)
  list(GET bounds 1 x1)
  list(GET bounds 2 y0)
  list(GET bounds 3 y1)
  list(GET bounds 4 r0)
  list(GET bounds 5 r1)
  list(GET bounds 6 expected_primary)
  if(x LESS x0 OR x GREATER x1 OR y LESS y0 OR y GREATER y1 OR r LESS r0 OR r GREATER r1)
    message(FATAL_ERROR "sphere ${i} at ${x}, ${y}, radius ${r}: outside ${bounds}")
  endif()
  if((primary AND NOT expected_primary) OR (NOT primary AND expected_primary))
    message(FATAL_ERROR "sphere ${i} at ${x}, ${y}: primary ${primary}, expected ${expected_primary}")
  endif()
endforeach()

execute_process(COMMAND ${RFD} capture calibrate ${photos} --overrides ${OUT}/overrides.toml --out ${OUT}/again.lp
                RESULT_VARIABLE code OUTPUT_QUIET ERROR_VARIABLE stderr)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "rfd capture calibrate --overrides failed (${code}): ${stderr}")
endif()
file(READ ${OUT}/lights.lp first)
file(READ ${OUT}/again.lp second)
if(NOT first STREQUAL second)
  message(FATAL_ERROR "the overrides did not give the same light file:\n${first}\n---\n${second}")
endif()

execute_process(COMMAND ${RFD} capture calibrate ${photos} --overrides ${OUT}/overrides.toml --drop 3
                        --drop field_0007.jpg --out ${OUT}/dropped.lp
                RESULT_VARIABLE code OUTPUT_QUIET ERROR_VARIABLE stderr)
file(STRINGS ${OUT}/dropped.lp lines)
list(LENGTH lines count)
list(GET lines 0 header)
if(NOT code EQUAL 0 OR NOT count EQUAL 11 OR NOT header STREQUAL "10" OR "${lines}" MATCHES "field_0002|field_0007")
  message(FATAL_ERROR "--drop 3 --drop field_0007.jpg: ${code} ${stderr}\n${lines}")
endif()
