# Draws the photographs the `rfd capture hdr` and `rfd capture calibrate` tests read, with
# oiiotool, into ${OUT}:
#  - bracket_N.tif: an 8-bit bracket of a radiance ramp (three decades, a different scale per
#    channel) through a gamma-2.2 camera at uneven exposure times, each time in EXIF;
#  - small.tif: a smaller image, for the size check;
#  - mirror_0.png, mirror_1.png: a black mirror sphere (centre 48,48, radius 40 px in a 96x96
#    image) with a 2x2 highlight whose pixel corners are (56,36) and (30,60): centroids (57,37)
#    and (31,61), seeing the lights at theta 41.6, phi 50.7 and theta 64.7, phi -142.6 deg;
#  - black.png: the sphere with no highlight; two.png: with two.
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
function(oiiotool)
  execute_process(COMMAND ${OIIOTOOL} ${ARGN} WORKING_DIRECTORY ${OUT} RESULT_VARIABLE code ERROR_VARIABLE stderr)
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "oiiotool ${ARGN} failed (${code}): ${stderr}")
  endif()
endfunction()
set(ramp fill:topleft=0.02,0.01,0.005:topright=2,1,0.5:bottomleft=0.2,0.1,0.05:bottomright=8,4,2)
set(i 0)
foreach(t 0.1 0.3 1 3.3)
  oiiotool(--pattern ${ramp} 48x32 3 --mulc ${t} --clamp:min=0:max=1 --powc 0.4545 -d uint8
           --attrib:type=float ExposureTime ${t} -o bracket_${i}.tif)
  math(EXPR i "${i} + 1")
endforeach()
oiiotool(--pattern ${ramp} 40x32 3 --clamp:min=0:max=1 --powc 0.4545 -d uint8 -o small.tif)
oiiotool(--create 96x96 3 --box:color=1,1,1:fill=1 56,36,57,37 -d uint8 -o mirror_0.png)
oiiotool(--create 96x96 3 --box:color=1,1,1:fill=1 30,60,31,61 -d uint8 -o mirror_1.png)
oiiotool(--create 96x96 3 -d uint8 -o black.png)
oiiotool(--create 96x96 3 --box:color=1,1,1:fill=1 56,36,57,37 --box:color=1,1,1:fill=1 30,60,31,61 -d uint8 -o two.png)
