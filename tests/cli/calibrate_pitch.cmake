# `rfd calibrate simulate-photo moire` and `rfd calibrate pitch` end to end: Design I's
# array 0.2 % too large and turned 0.5 deg on the moire sheet, photographed hand-held at a
# phone's lower resolution, read back into a design file rfd then loads with the measured
# pitch; two runs give the same bytes; what cannot be read or makes no sense is refused with
# the reason and nothing written.
include(${CMAKE_CURRENT_LIST_DIR}/run_rfd.cmake)
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
set(design ${DESIGN})

run(0 calibrate simulate-photo moire epson_stylus_pro_4800 --design ${design} --pitch-error 0.002
    --array-rotation 0.5 --camera-pixels 2000 --camera-tilt 20 --camera-turn 30 --blur 1 --photons 3000
    --out ${OUT}/photo.jpg)
foreach(run a b)
  run(0 calibrate pitch ${design} ${OUT}/photo.jpg --out ${OUT}/${run}.toml --report ${OUT}/${run})
endforeach()
expect("pitch along a row: 2.362[0-9]+ mm, design 2.357851 mm: \\+0.(199|200|201)[0-9] %")
expect("rows turned \\+0.(49|50|51)[0-9]+ deg")
expect_same_file(${OUT}/a.toml ${OUT}/b.toml "two calibrations of one photograph differ")
expect_same_file(${OUT}/a/lenslets.csv ${OUT}/b/lenslets.csv "two reports of one photograph differ")
# The written design is a design, with the measured pitch.
run(0 design show ${OUT}/a.toml)
file(READ ${OUT}/a.toml written)
if(NOT written MATCHES "pitch_mm = 2.362[0-9]+ +# measured by rfd calibrate pitch")
  message(FATAL_ERROR "the written design does not hold the measured pitch")
endif()

# Refused, with the reason, nothing written.
run(2 calibrate pitch ${design} ${OUT}/photo.jpg --sheet-scale 0,1 --out ${OUT}/never.toml)
expect("--sheet-scale: Value 0 not in range")
# Design II's 6 x 5 array, laid whole on a band, needs a tilted photograph (its lenslet images
# lie 13.4 mm above the sheet, magnified by an amount only the camera's height tells).
run(0 calibrate simulate-photo moire epson_stylus_pro_4800 --design ${DESIGN2} --array-on x --camera-pixels 1500
    --out ${OUT}/frontal.jpg)
run(2 calibrate pitch ${DESIGN2} ${OUT}/frontal.jpg --out ${OUT}/never.toml)
expect("frontal.jpg: the photograph is within 10 deg of frontal")
run(2 calibrate pitch ${design} ${OUT}/photo.jpg --out ${OUT}/never.txt)
expect("expected a .toml file")
run(2 calibrate simulate-photo moire epson_stylus_pro_4800 --design ${design} --pitch-error -1 --out ${OUT}/never.jpg)
expect("--pitch-error: Value -1 not in range")
run(2 calibrate simulate-photo moire epson_stylus_pro_4800 --out ${OUT}/never.jpg)
expect("the moire sheet needs a design")
# The array laid beside the measuring block: its lines are not under the lenslets.
run(0 calibrate simulate-photo moire epson_stylus_pro_4800 --design ${design} --camera-pixels 2000
    --array-shift 0,150 --out ${OUT}/away.jpg)
run(2 calibrate pitch ${design} ${OUT}/away.jpg --out ${OUT}/never.toml)
expect("away.jpg: ")
foreach(never never.toml never.txt never.jpg)
  if(EXISTS ${OUT}/${never})
    message(FATAL_ERROR "a refused command wrote ${never}")
  endif()
endforeach()
