# Implicit relighting end to end on a small virtual light stage set of the snooker scene:
#  - capture implicit writes the training set, the held-out photos and truth, and probe.json
#    with a box that lies on the ball;
#  - train reads probe.json; predict relights from a photograph and from designed lighting
#    (the ball's material is known), with coefficients that sum to 1 (before the second pass
#    adds a little light), byte-identically twice;
#  - sweep writes one CSV row per eta and the comparison images;
#  - bad input is an input error that names what was wrong, and writes nothing.
include(${CMAKE_CURRENT_LIST_DIR}/run_rfd.cmake)
file(REMOVE_RECURSE ${OUT})

run(0 capture implicit ${SCENE} --resolution 96x60 --samples-per-pixel 1 --lights 24 --held-out 3
    --out ${OUT}/set --json)
expect("\"probe\": \"snooker_ball\"")
foreach(file training/field.lp training/probe.json training/field_0023.exr test/photos/field.lp
        test/photos/probe.json test/truth/field_0002.exr)
  if(NOT EXISTS ${OUT}/set/${file})
    message(FATAL_ERROR "capture implicit did not write ${file}")
  endif()
endforeach()
# The ball (centre x = 90 mm on a 300 mm card seen 96 pixels wide) lies right of centre.
file(READ ${OUT}/set/training/probe.json probe)
string(JSON box_x GET "${probe}" probe_box 0)
string(JSON box_w GET "${probe}" probe_box 2)
if(box_x LESS 60 OR box_w LESS 10 OR box_w GREATER 20)
  message(FATAL_ERROR "probe box off the ball: ${probe}")
endif()
string(JSON exponent GET "${probe}" probe_material exponent)
if(NOT exponent EQUAL 50)
  message(FATAL_ERROR "probe material not recorded: ${probe}")
endif()

run(0 relight implicit train ${OUT}/set/training --probe-size 32 --out ${OUT}/model)
expect("trained .* from 24 images of 96 x 60")
expect("principal comps\\. +2[0-3] per channel")

foreach(run a b)
  run(0 relight implicit predict ${OUT}/model --probe ${OUT}/set/test/photos/field_0000.exr --eta 1e-6
      --no-second-pass --out ${OUT}/${run}.exr --probe-out ${OUT}/${run}_probe.exr --coefficients ${OUT}/${run}.csv --json)
endforeach()
expect("\"coefficient_sum\": (0\\.9999|1\\.0)")
expect_same_file(${OUT}/a.exr ${OUT}/b.exr "two identical predictions differ")
file(STRINGS ${OUT}/a.csv lines)
list(LENGTH lines count)
if(NOT count EQUAL 25)
  message(FATAL_ERROR "coefficients CSV has ${count} lines, expected a header and 24 images")
endif()
run(0 relight implicit predict ${OUT}/model --light 30,45,10 --out ${OUT}/designed.exr)
expect("predicted .*designed\\.exr from 24 training images")

run(0 relight implicit sweep ${OUT}/model --test ${OUT}/set/test --etas 0,1e-6,1e-3 --examples 1 --out ${OUT}/sweep)
expect("best eta")
file(STRINGS ${OUT}/sweep/eta_sweep.csv lines)
list(LENGTH lines count)
if(NOT count EQUAL 4)
  message(FATAL_ERROR "eta_sweep.csv has ${count} lines, expected a header and 3 etas")
endif()
foreach(file light_00.png light_00_probe.png)
  if(NOT EXISTS ${OUT}/sweep/${file})
    message(FATAL_ERROR "sweep did not write ${file}")
  endif()
endforeach()

# Bad input.
run(2 relight implicit train ${OUT}/set/training --probe-box 1,2,x,4 --out ${OUT}/never)
expect("--probe-box 1,2,x,4: expected X,Y,WIDTH,HEIGHT")
run(2 relight implicit train ${OUT}/set/training --probe-box 80,10,40,40 --out ${OUT}/never)
expect("field_0000\\.exr")
file(MAKE_DIRECTORY ${OUT}/plain)
file(COPY ${OUT}/set/training/field_0000.exr ${OUT}/set/training/field_0001.exr DESTINATION ${OUT}/plain)
run(2 relight implicit train ${OUT}/plain --out ${OUT}/never)
expect("give --probe-box")
run(0 relight implicit train ${OUT}/plain --probe-box 60,20,16,16 --out ${OUT}/plain_model)
run(2 relight implicit predict ${OUT}/plain_model --light 30,45 --out ${OUT}/never.exr)
expect("does not know its probe's material")
run(2 relight implicit sweep ${OUT}/model --test ${OUT}/set/test --etas 0,-1 --out ${OUT}/never)
expect("--etas: expected comma-separated numbers >= 0, got '-1'")
run(2 capture implicit ${SCENE} --probe no_such_ball --lights 4 --held-out 0 --out ${OUT}/never)
expect("--probe no_such_ball: no object of that name")
if(EXISTS ${OUT}/never OR EXISTS ${OUT}/never.exr)
  message(FATAL_ERROR "a failed command left output behind")
endif()
