# `rfd capture calibrate` end to end on the mirror spheres of capture_tools_data.cmake: the
# light file lists the field images (relative to its folder) with the directions seen by the
# highlights, theta and phi within 0.1 degrees of the closed form at the highlight centroids
# (the estimate averages the 2x2 pixels' directions, not the centroid's).
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT}/field)
execute_process(COMMAND ${RFD} capture calibrate --sphere 48,48,40 ${DATA}/mirror_0.png ${DATA}/mirror_1.png
                        --images ${OUT}/field/a.exr ${OUT}/field/b.exr --out ${OUT}/field/lights.lp --json
                RESULT_VARIABLE code OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "rfd capture calibrate failed (${code}): ${stderr}")
endif()
# Closed form: n = ((cx - 48) / 40, -(cy - 48) / 40, nz), l = 2 nz n - z gives theta 41.57,
# phi 50.71 and theta 64.68, phi -142.59; the patterns below allow about 0.1 degrees.
set(expected "41\\.[56]" "50\\.[67]" "64\\.[67]" "-142\\.[56]")
set(k 0)
foreach(i 0 1)
  foreach(key theta_deg phi_deg)
    string(JSON value GET "${stdout}" lights ${i} ${key})
    list(GET expected ${k} pattern)
    if(NOT value MATCHES "^${pattern}")
      message(FATAL_ERROR "light ${i}: ${key} = ${value}, expected ${pattern}")
    endif()
    math(EXPR k "${k} + 1")
  endforeach()
endforeach()
file(STRINGS ${OUT}/field/lights.lp lines)
list(LENGTH lines count)
list(GET lines 0 header)
list(GET lines 1 first)
list(GET lines 2 second)
if(NOT count EQUAL 3 OR NOT header STREQUAL "2" OR NOT first MATCHES "^a\\.exr 0\\.42[0-9]* 0\\.51[0-9]* 0\\.74[0-9]*$"
   OR NOT second MATCHES "^b\\.exr -0\\.71[0-9]* -0\\.54[0-9]* 0\\.42[0-9]*$")
  message(FATAL_ERROR "lights.lp: ${lines}")
endif()
