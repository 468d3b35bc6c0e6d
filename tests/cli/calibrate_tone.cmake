# `rfd calibrate simulate-photo` and `rfd calibrate tone` end to end: a wedge printed by a
# printer whose curve is not the profile's (printers' true density 1.6, gamma 1.7),
# photographed hand-held, read back into a profile that `rfd print wedge` then predicts
# with; the profile's values land near the truth, two runs give the same bytes, and what
# cannot be read is refused with the reason and nothing written.
include(${CMAKE_CURRENT_LIST_DIR}/run_rfd.cmake)
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
file(WRITE ${OUT}/true.toml "[printer]\nname = \"true\"\ndpi_x = 2880\ndpi_y = 1440\ngamma = 1.7\nmax_density = 1.6\nblack_level = 0.03\n")

set(phone --camera-tilt 25 --camera-turn 30 --camera-roll 5 --blur 1.2 --vignetting 0.3 --photons 3000)
run(0 calibrate simulate-photo wedge epson_stylus_pro_4800 --true-printer ${OUT}/true.toml ${phone} --out ${OUT}/phone.jpg)
foreach(run a b)
  run(0 calibrate tone epson_stylus_pro_4800 ${OUT}/phone.jpg --out ${OUT}/${run}.toml)
endforeach()
expect("max_density 1.6[01][0-9] \\(was 2.000\\)")
expect("power law gamma 1.[67][0-9]+ \\(was 2.200\\)")
expect_same_file(${OUT}/a.toml ${OUT}/b.toml "two calibrations of one photograph differ")
# The measured profile is a profile: the wedge printed with it predicts the measured curve.
run(0 print wedge --printer ${OUT}/a.toml --out ${OUT}/check.pdf)
expect("code +0 +ink 1.000 +predicted transmittance 0.02[45]")

# Refused, naming the photograph, nothing written.
run(0 calibrate simulate-photo wedge epson_stylus_pro_4800 --frame-fill 0.1 --out ${OUT}/far.png)
run(2 calibrate tone epson_stylus_pro_4800 ${OUT}/far.png --out ${OUT}/never.toml)
expect("far.png: (the wedge's patches are [0-9.]+ pixels across|cannot find the sheet)")
run(2 calibrate tone epson_stylus_pro_4800 ${OUT}/phone.jpg --out ${OUT}/never.txt)
expect("expected a .toml file")
run(2 calibrate tone epson_stylus_pro_4800 ${OUT}/phone.jpg --steps 300 --out ${OUT}/never.toml)
if(EXISTS ${OUT}/never.toml)
  message(FATAL_ERROR "a refused calibration wrote its profile")
endif()
