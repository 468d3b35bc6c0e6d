# `rfd simulate verdict` from summaries written by hand: the PSNR over the field of view
# against the field's brightest value (a dark direction does not fail the display), a
# tolerance the sweep never reached shown as a lower bound, and a damaged summary refused.
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT}/compare ${OUT}/tolerance)
include(${CMAKE_CURRENT_LIST_DIR}/run_rfd.cmake)

# Two directions inside the field of view: 40 dB against a peak of 1, and a dark one whose
# residue (mse 1e-6) would be -20 dB against its own peak of 1e-4 but is 60 dB against 1.
# The summaries hold every key rfd writes (a missing one is refused, as at the end).
file(WRITE ${OUT}/compare/summary.json [=[
{"design": "Design II", "pattern": "pattern.exr", "field": "field", "model": "exact", "model_choice": "auto",
 "paraxial_error_dots": null, "rays_per_side": 8, "lenslets": [6, 5], "display_range_deg": 16, "field_peak": 1.0,
 "macro_pixel_core": {"fraction": 1, "magnification": 1},
 "directions": [
  {"image": "light.png", "field_theta_deg": 0, "field_phi_deg": 0, "display_angle_deg": 0, "inside_fov": true, "crosstalk_free": true, "efficiency": 0.4, "peak": 1.0, "mse": 1e-4, "psnr_db": null, "psnr_own_peak_db": 40, "fitted_gain": 1, "psnr_fitted_db": null, "psnr_cell_db": null, "rays": 64},
  {"image": "light.png", "field_theta_deg": 3, "field_phi_deg": 0, "display_angle_deg": 3, "inside_fov": true, "crosstalk_free": true, "efficiency": 0.4, "peak": 1e-4, "mse": 1e-6, "psnr_db": null, "psnr_own_peak_db": -20, "fitted_gain": 1, "psnr_fitted_db": null, "psnr_cell_db": null, "rays": 64}],
 "inside_fov": 2, "min_psnr_in_fov_db": null, "mean_psnr_in_fov_db": null, "min_psnr_fitted_in_fov_db": null,
 "mean_psnr_fitted_in_fov_db": null, "min_psnr_cell_in_fov_db": null, "crosstalk_free": 2,
 "min_psnr_crosstalk_free_db": null, "mean_psnr_crosstalk_free_db": null, "min_psnr_fitted_crosstalk_free_db": null,
 "mean_psnr_fitted_crosstalk_free_db": null, "min_psnr_cell_crosstalk_free_db": null,
 "accuracy_directions": 0, "accuracy": []}
]=])
file(WRITE ${OUT}/tolerance/summary.json [=[
{"design": "Design II", "threshold_db": 30, "model": "paraxial", "lights": 3, "nominal_peak": 1, "summary": "",
 "curves": [
  {"kind": "shift", "unit": "mm", "tolerance": 0.4, "max": 1.0, "within_sweep": true, "sweep": [], "refinement": [], "chart": "shift.svg"},
  {"kind": "rotation", "unit": "deg", "tolerance": 0.9, "max": 2.0, "within_sweep": true, "sweep": [], "refinement": [], "chart": "rotation.svg"},
  {"kind": "pitch_error", "unit": "ppm", "tolerance": 5000, "max": 20000, "within_sweep": true, "sweep": [], "refinement": [], "chart": "pitch_error.svg"},
  {"kind": "spacer", "unit": "mm", "tolerance": null, "max": 0.75, "within_sweep": false, "sweep": [], "refinement": [], "chart": "spacer.svg"}]}
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
expect("summary.json: not what rfd writes there")
