# `rfd simulate verdict` from summaries written by hand: the PSNR over the field of view
# against the field's brightest value (a dark direction does not fail the display), a
# tolerance the sweep never reached shown as a lower bound, and a damaged summary refused.
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT}/compare ${OUT}/tolerance)
include(${CMAKE_CURRENT_LIST_DIR}/run_rfd.cmake)

# Two directions inside the field of view: 40 dB against a peak of 1, and a dark one whose
# residue (mse 1e-6) would be -20 dB against its own peak of 1e-4 but is 60 dB against 1.
file(WRITE ${OUT}/compare/summary.json [=[
{"directions": [
  {"display_angle_deg": 0, "inside_fov": true, "crosstalk_free": true, "mse": 1e-4, "peak": 1.0},
  {"display_angle_deg": 3, "inside_fov": true, "crosstalk_free": true, "mse": 1e-6, "peak": 1e-4}]}
]=])
file(WRITE ${OUT}/tolerance/summary.json [=[
{"curves": [
  {"kind": "shift", "tolerance": 0.4, "max": 1.0},
  {"kind": "rotation", "tolerance": 0.9, "max": 2.0},
  {"kind": "pitch_error", "tolerance": 5000, "max": 20000},
  {"kind": "spacer", "tolerance": null, "max": 0.75}]}
]=])
run(0 simulate verdict ${DESIGN} --compare ${OUT}/compare --tolerance ${OUT}/tolerance --out ${OUT}/verdict.json)
expect("PSNR over the FOV +mean 50\\.00 dB, min 40\\.00 dB")
expect("spacer 0\\.75 mm or more")
file(READ ${OUT}/verdict.json json)
string(JSON at_least GET "${json}" tolerances at_least 0)
if(NOT at_least STREQUAL "spacer")
  message(FATAL_ERROR "verdict.json does not mark the spacer's tolerance as a lower bound: ${json}")
endif()

file(WRITE ${OUT}/tolerance/summary.json "{\"curves\": 3}")
run(2 simulate verdict ${DESIGN} --compare ${OUT}/compare --tolerance ${OUT}/tolerance)
expect("lacks what rfd simulate writes")
