# What calibration is for, end to end: the lens array is 0.1 % larger than its design says.
# A pattern encoded for the design, printed and laid on that array, shows less of its field
# than one encoded for the true array; the array's pitch measured from a simulated photograph
# of the moire sheet (rfd calibrate pitch --out), the pattern encoded again for the measured
# design recovers what was lost. Judged by rfd simulate compare on the true array, light on
# the axis (the one crosstalk-free direction), against the field.
include(${CMAKE_CURRENT_LIST_DIR}/run_rfd.cmake)
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})

# The true array: Design I's with every pitch 1.001 times (lenses per cm^2 over 1.001^2).
file(READ ${DESIGN} text)
string(REGEX REPLACE "lenses_per_cm2 = 20\\.77[^\n]*" "lenses_per_cm2 = 20.72852222702373" text "${text}")
if(NOT text MATCHES "20\\.72852222702373")
  message(FATAL_ERROR "design1.toml no longer says lenses_per_cm2 = 20.77: update this test")
endif()
file(WRITE ${OUT}/true.toml "${text}")

run(0 capture render ${SCENE} --samples-per-pixel 1 --resolution 63x73 --lights 60 --out ${OUT}/field)
run(0 calibrate simulate-photo moire inkjet_720 --design ${DESIGN} --pitch-error 0.001 --pitch-error-y 0.001
    --camera-tilt 15 --blur 1 --photons 3000 --out ${OUT}/moire.jpg)
run(0 calibrate pitch ${DESIGN} ${OUT}/moire.jpg --printer inkjet_720 --out ${OUT}/measured.toml)
expect("pitch along a row: [0-9.]+ mm, design [0-9.]+ mm: \\+0\\.(09[5-9]|10[0-5])[0-9]* %")

# A PSNR as an integer in thousandths of a dB (CMake's arithmetic is integer).
function(psnr_milli_db folder out)
  file(READ ${folder}/summary.json json)
  string(JSON value GET "${json}" mean_psnr_crosstalk_free_db)
  if(NOT value MATCHES "^([0-9]+)\\.([0-9][0-9][0-9])")
    message(FATAL_ERROR "${folder}: PSNR '${value}' is not a number of dB")
  endif()
  math(EXPR milli "${CMAKE_MATCH_1} * 1000 + 1${CMAKE_MATCH_2} - 1000")
  set(${out} ${milli} PARENT_SCOPE)
endfunction()

foreach(encoded nominal:${DESIGN} measured:${OUT}/measured.toml true:${OUT}/true.toml)
  string(REGEX REPLACE ":.*" "" name ${encoded})
  string(REGEX REPLACE "^[a-z]+:" "" for ${encoded})
  run(0 pattern encode ${for} ${OUT}/field --printer inkjet_720 --out ${OUT}/${name}.exr)
  run(0 simulate compare ${OUT}/true.toml ${OUT}/${name}.exr ${OUT}/field --encoded-for ${for} --sweep 1
      --out ${OUT}/${name})
  psnr_milli_db(${OUT}/${name} ${name})
endforeach()
message(STATUS "on the true array: encoded for the design ${nominal}, for the measured pitch ${measured}, "
               "for the true pitch ${true} (thousandths of a dB)")
math(EXPR lost "${true} - ${nominal}")
math(EXPR left "${true} - ${measured}")
if(lost LESS 100)
  message(FATAL_ERROR "the pitch error cost only ${lost} thousandths of a dB: the test cannot tell")
endif()
if(left GREATER 20 OR left LESS -20)
  message(FATAL_ERROR "the calibrated pattern is ${left} thousandths of a dB from the true one's (lost: ${lost})")
endif()

# A print of another kind of design does not fit the array.
run(2 simulate compare ${OUT}/true.toml ${OUT}/nominal.exr ${OUT}/field --encoded-for ${DESIGN2} --sweep 1
    --out ${OUT}/never)
expect("--encoded-for.*another kind")
