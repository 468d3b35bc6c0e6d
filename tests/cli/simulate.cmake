# `rfd simulate` end to end on Design II: a bars field encoded at the design's resolution,
# predicted under a light (deterministic: twice gives byte-identical images), the per-lenslet
# picture, and the errors a user meets: a light that does not reach the display from behind,
# a pattern made at another resolution than the printer's (Designs III and IV:
# simulate_angular.cmake).
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
include(${CMAKE_CURRENT_LIST_DIR}/run_rfd.cmake)

run(0 pattern field bars --resolution 12x10 --spread 8 --out ${OUT}/bars)
run(0 pattern encode ${DESIGN} ${OUT}/bars --out ${OUT}/bars.exr)
foreach(name a b)
  run(0 simulate ${DESIGN} ${OUT}/bars.exr --light 10,180 --light 10,0,0:0:1 --out ${OUT}/${name}.exr
      --lenslets ${OUT}/${name}_lenslets.exr --json)
endforeach()
if(NOT last_output MATCHES "\"model\": \"(paraxial|exact)\"" OR NOT last_output MATCHES "\"directions\": 2"
   OR NOT last_output MATCHES "\"rays_crossed\": 0")
  message(FATAL_ERROR "unexpected summary: ${last_output}")
endif()
expect_same_file(${OUT}/a.exr ${OUT}/b.exr "simulating twice gave different images")
if(NOT EXISTS ${OUT}/a_lenslets.exr)
  message(FATAL_ERROR "no per-lenslet picture")
endif()

# The diffraction model: the exact rays and the pattern seen through the lenslets' PSF, whose
# central lobe is a sixth of a dot at 2880 x 1440 dpi: the picture barely changes.
run(0 simulate ${DESIGN} ${OUT}/bars.exr --light 10,180 --light 10,0,0:0:1 --model exact --out ${OUT}/exact.exr)
run(0 simulate ${DESIGN} ${OUT}/bars.exr --light 10,180 --light 10,0,0:0:1 --model diffraction --out ${OUT}/wave.exr
    --json)
if(NOT last_output MATCHES "\"diffraction\": true" OR NOT last_output MATCHES "\"diffraction_lobe_dots\": 0[.]1")
  message(FATAL_ERROR "--model diffraction: unexpected summary: ${last_output}")
endif()
find_program(OIIOTOOL oiiotool REQUIRED)
execute_process(COMMAND ${OIIOTOOL} ${OUT}/exact.exr ${OUT}/wave.exr --fail 0.005 --diff
                RESULT_VARIABLE code OUTPUT_VARIABLE diff)
if(NOT code EQUAL 0 OR NOT diff MATCHES "[1-9][0-9]* pixels [(][0-9]+%[)] over 1e-06")
  message(FATAL_ERROR "--model diffraction: not a slight blur of the exact picture: ${diff}")
endif()

# The predicted display as an RTI set, read back by rfd's own light file reader.
run(0 simulate rti ${DESIGN} ${OUT}/bars.exr --count 6 --out ${OUT}/rti)
expect("wrote .*display.lp: 6 pictures of 6 x 5")
run(0 relight render ${OUT}/rti --light 2,0 --out ${OUT}/rti_lit.png)
expect("relit .*rti \\(6 images\\)")

# --exposure -1: the same picture at half the value.
run(0 simulate ${DESIGN} ${OUT}/bars.exr --light 10,180 --light 10,0,0:0:1 --exposure -1 --out ${OUT}/half.exr)
execute_process(COMMAND ${OIIOTOOL} ${OUT}/a.exr --mulc 0.5 ${OUT}/half.exr --diff --fail 1e-6
                RESULT_VARIABLE code OUTPUT_VARIABLE diff)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "--exposure -1 is not half the picture: ${diff}")
endif()

# Lights in the display's frame by default: with the pattern tilted by 45 deg, 0,0 is the
# display's axis (the field's 45,90); in the field's frame (--frame field) 0,0 is 45 deg off
# the axis, outside the field of view, and says so.
run(0 pattern encode ${DESIGN} ${OUT}/bars --tilt 45 --allow-partial --out ${OUT}/tilted.exr)
run(0 simulate ${DESIGN} ${OUT}/tilted.exr --light 0,0 --out ${OUT}/tilted_axis.exr --json)
string(JSON axis_angle GET "${last_output}" light_checks 0 angle_to_axis_deg)
string(JSON field_theta GET "${last_output}" light_checks 0 field_deg 0)
string(JSON field_phi GET "${last_output}" light_checks 0 field_deg 1)
string(JSON warning GET "${last_output}" light_checks 0 warning)
if(NOT axis_angle EQUAL 0 OR field_theta LESS 44.999 OR field_theta GREATER 45.001 OR field_phi LESS 89.999
   OR field_phi GREATER 90.001 OR NOT warning STREQUAL "")
  message(FATAL_ERROR "the display's axis is not the field's 45,90: ${last_output}")
endif()
run(0 simulate ${DESIGN} ${OUT}/tilted.exr --frame field --light 0,0 --out ${OUT}/tilted_field.exr)
expect("warning: --light 0,0: 45.0 deg from the display's axis, outside its field of view \\(wrap-over at [0-9.]+ deg")

# An environment map (a 16 x 8 latitude-longitude image: the bars field's first image).
run(0 pattern field bars --resolution 16x8 --spread 8 --out ${OUT}/sky)
run(0 simulate ${DESIGN} ${OUT}/bars.exr --envmap ${OUT}/sky/bars_0000.exr --out ${OUT}/env.exr --json)
if(NOT last_output MATCHES "\"directions\": [1-9]" OR NOT last_output MATCHES "\"sampled_size\": \\[[^]]*16")
  message(FATAL_ERROR "unexpected environment summary: ${last_output}")
endif()
find_program(OIIOTOOL oiiotool REQUIRED)
execute_process(COMMAND ${OIIOTOOL} --pattern constant:color=0.5,-1,0.5 16x8 3 -d float -o ${OUT}/negative.exr
                RESULT_VARIABLE code)
run(2 simulate ${DESIGN} ${OUT}/bars.exr --envmap ${OUT}/negative.exr --out ${OUT}/never.exr)
if(NOT last_output MATCHES "negative.exr: pixel \\(0, 0\\) channel 1 is -1")
  message(FATAL_ERROR "unexpected message: ${last_output}")
endif()
run(2 simulate ${DESIGN} ${OUT}/bars.exr --envmap ${OUT}/bars/bars_0000.exr --out ${OUT}/never.exr)
if(NOT last_output MATCHES "twice as wide as high, got 12 x 10")
  message(FATAL_ERROR "unexpected message: ${last_output}")
endif()

run(2 simulate ${DESIGN} ${OUT}/bars.exr --light 90,0 --out ${OUT}/never.exr)
if(NOT last_output MATCHES "light 1: a light must shine through the display from behind")
  message(FATAL_ERROR "unexpected message: ${last_output}")
endif()
# A pattern encoded at another resolution is printed at it (the one the file records);
# with a printer of another resolution it is refused, giving both sizes.
run(0 pattern encode ${DESIGN} ${OUT}/bars --dpi 360x180 --out ${OUT}/low.exr)
run(0 simulate ${DESIGN} ${OUT}/low.exr --light 0,0 --out ${OUT}/low_predicted.exr)
run(2 simulate ${DESIGN} ${OUT}/low.exr --light 0,0 --printer epson_stylus_pro_4800 --out ${OUT}/never.exr)
if(NOT last_output MATCHES "low\\.exr: the pattern is 341 x 171 dots at 360 x 180 dpi")
  message(FATAL_ERROR "unexpected message: ${last_output}")
endif()
if(EXISTS ${OUT}/never.exr)
  message(FATAL_ERROR "a refused simulation wrote its output")
endif()
