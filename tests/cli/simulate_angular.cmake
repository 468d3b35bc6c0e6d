# `rfd simulate` end to end on Designs III and IV: coarse copies of the presets (printer at
# 254 / 127 dpi; Design IV with 2 x 2 macro-pixels) so that the patterns stay small; the
# letters and diamonds of `rfd pattern encode-angular` predicted under a light, seen from
# two directions and an eye, with the macro-pixel pictures and an angular distribution;
# deterministic (twice gives byte-identical images); and the errors a user meets.
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
include(${CMAKE_CURRENT_LIST_DIR}/run_rfd.cmake)

file(READ ${DESIGN3} text)
string(REPLACE "dpi_x = 2880\ndpi_y = 1440" "dpi_x = 254\ndpi_y = 254" text "${text}")
file(WRITE ${OUT}/design3.toml "${text}")
file(READ ${DESIGN4} text)
string(REPLACE "dpi_x = 2880\ndpi_y = 1440" "dpi_x = 127\ndpi_y = 127" text "${text}")
string(REPLACE "count = [7, 7]" "count = [2, 2]" text "${text}")
file(WRITE ${OUT}/design4.toml "${text}")

run(0 pattern encode-angular ${OUT}/design3.toml --procedural letters --table 33 --out ${OUT}/letters.exr)
# The judge: the display seen from a grid of viewpoints under a grid of lights against the
# letters relit and viewed the same way; the held-out grids; FIELD or --procedural needed.
run(0 simulate compare ${OUT}/design3.toml ${OUT}/letters.exr --procedural letters --light-grid 3 --view-grid 2
    --lens-rays 32 --out ${OUT}/judge --json)
expect("\"pairs\": 36")
expect("\"psnr_db\": [1-9][0-9]")
if(NOT EXISTS ${OUT}/judge/pairs.csv OR NOT EXISTS ${OUT}/judge/summary.json)
  message(FATAL_ERROR "simulate compare (Design III) wrote no pairs.csv or summary.json")
endif()
run(0 simulate compare ${OUT}/design3.toml ${OUT}/letters.exr --procedural letters --light-grid 3 --view-grid 2
    --lens-rays 32 --held-out --out ${OUT}/judge_held --json)
expect("\"pairs\": 4,")
run(2 simulate compare ${OUT}/design3.toml ${OUT}/letters.exr --out ${OUT}/judge_bad)
expect("give FIELD")

# Under an environment map (a 16 x 8 latitude-longitude image: a bars field's first image).
run(0 pattern field bars --resolution 16x8 --spread 8 --out ${OUT}/sky)
run(0 simulate ${OUT}/design3.toml ${OUT}/letters.exr --envmap ${OUT}/sky/bars_0000.exr --out ${OUT}/env.exr
    --lens-rays 24 --json)
expect("\"envmap\"")
expect("\"directions\": [1-9]")
foreach(name a b)
  run(0 simulate ${OUT}/design3.toml ${OUT}/letters.exr --light 5,0 --view 0,0 --view 6,90 --out ${OUT}/${name}.exr
      --macro ${OUT}/${name}_macro.exr --distribution 0,0 --distribution-out ${OUT}/${name}_dist.exr --lens-rays 48 --json)
endforeach()
expect("\"design_kind\": \"III\"")
expect("\"model\": \"exact\"")
expect("\"meso_pixels\": \\[[ \n]*6,[ \n]*5[ \n]*\\]")
expect("\"optical_efficiency\": 0\\.[5-9]")
foreach(file _view1.exr _view2.exr _macro_view1.exr _dist_0_0.exr)
  if(NOT EXISTS ${OUT}/a${file})
    message(FATAL_ERROR "missing output a${file}")
  endif()
  expect_same_file(${OUT}/a${file} ${OUT}/b${file} "simulating twice gave different ${file}")
endforeach()

run(0 pattern encode-angular ${OUT}/design4.toml --procedural diamonds --table 17 --out ${OUT}/diamonds.exr)
run(0 simulate ${OUT}/design4.toml ${OUT}/diamonds.exr --light 3,270 --eye 0,0,600 --model paraxial --zoom 4
    --out ${OUT}/design4.png --macro ${OUT}/design4_macro.png --lens-rays 32)
expect("12 x 10 meso-pixels \\(2 x 2 macro-pixels\\)")
expect("model +paraxial \\(as asked\\)")
if(NOT EXISTS ${OUT}/design4.png OR NOT EXISTS ${OUT}/design4_macro.png)
  message(FATAL_ERROR "no Design IV pictures")
endif()

# Errors: what is wrong, and nothing written.
run(2 simulate ${OUT}/design3.toml ${OUT}/letters.exr --light 0,0 --view 5 --out ${OUT}/never.exr)
expect("--view '5': expected 2 numbers separated by commas")
run(2 simulate ${OUT}/design3.toml ${OUT}/letters.exr --light 0,0 --distribution 1,0 --distribution-out ${OUT}/never_d.exr --out ${OUT}/never.exr)
expect("distribution 1: macro-pixel 1,0 is off the 1 x 1 grid")
run(2 simulate ${OUT}/design3.toml ${OUT}/letters.exr --light 0,0 --rays 8 --out ${OUT}/never.exr)
expect("--rays-per-side, --lenslets and --pixels-per-lenslet are for Designs I and II")
run(2 simulate ${OUT}/design3.toml ${OUT}/letters.exr --light 0,0 --eye 0,0,-3 --out ${OUT}/never.exr)
expect("view 1: an eye must be in front of the display")
run(2 simulate ${OUT}/design3.toml ${OUT}/letters.exr --light 0,0 --frame display --out ${OUT}/never.exr)
expect("Designs III and IV take --light in the field's frame \\(--frame field\\)")
run(2 simulate ${OUT}/design3.toml ${OUT}/letters.exr --light 90,0 --out ${OUT}/never.exr)
expect("light 1: a light must shine through the display from behind")
run(2 simulate ${OUT}/design4.toml ${OUT}/letters.exr --light 0,0 --out ${OUT}/never.exr)
expect("letters\\.exr: the pattern is")
if(EXISTS ${OUT}/never.exr OR EXISTS ${OUT}/never_d_0_0.exr)
  message(FATAL_ERROR "a refused simulation wrote its output")
endif()
