#pragma once
// rfd's own photographs of the pitch-calibration set-up, for trying `rfd calibrate pitch`
// without a printer: the moire sheet (print/moire.hpp) mounted in the display in place of the
// pattern, lit from behind by a distant light (the sun), photographed from the front.
//
// Each lenslet focuses the light on the sheet and the diffuser shows how much of it the
// sheet's lines let through: the display's own forward model (optics::DisplaySimulator, the
// exact tracer) with the sheet as its transparency. Around the display the camera sees the
// sheet itself against the light, with its registration marks. The diffuser lies nearer the
// camera than the sheet, so it is drawn where the camera sees it (parallax), then the camera
// (calibrate/camera.hpp) adds perspective, blur, vignetting, noise.
//
// Frames: the array's (optics::Lattice: mm, x along a row, y up as the camera sees it, origin
// on its axis, the design's nominal pitch) and the page's (print/layout.hpp: mm, y down). An
// array lying on the sheet with its rows turned by `rotation_deg` counter-clockwise (as the
// camera sees it) and its pitch (1 + pitch_error) times the design's puts array point a at
//     page = centre + F R(rotation) diag(1 + pitch_error_x, 1 + pitch_error_y) a,
// F = diag(1, -1) (the page's y points down). Lines on the sheet sample the same map.
//
// Example: ArrayMounting mounting; mounting.pitch_error_x = 0.001;
//          Image photo = simulated_moire_photo(design, sheet, printer, {mounting}, camera);

#include <Eigen/Core>

#include "calibrate/camera.hpp"
#include "core/image.hpp"
#include "optics/design.hpp"
#include "print/moire.hpp"
#include "print/printer.hpp"

namespace rfd::calibrate {

/// How the lens array lies on the printed sheet (see the header comment).
struct ArrayMounting {
    Eigen::Vector2d centre{105.0, 148.5};  ///< page point under the array's axis, mm
    double rotation_deg = 0.0;             ///< of the rows against the sheet's x, counter-clockwise
    double pitch_error_x = 0.0;            ///< along a row: true pitch / design pitch - 1
    double pitch_error_y = 0.0;            ///< across the rows
};

/// Which measuring bands the array lies on: both (an array taller than the two), or one.
enum class MeasuringBands { Both, X, Rows };

/// The middle of the measuring bands (page 1): where a user lays the array.
Eigen::Vector2d measuring_centre(const print::MoireSheet& sheet, MeasuringBands which = MeasuringBands::Both);

/// The 2 x 2 part of the array-to-page map of the header comment.
Eigen::Matrix2d array_to_page(const ArrayMounting& mounting);

/// What is photographed: the mounting and the sun's direction.
struct MoireScene {
    ArrayMounting mounting;
    /// The light's direction of travel, from behind toward the camera (z > 0, the display's
    /// frame: optics/display.hpp).
    Eigen::Vector3d light = Eigen::Vector3d::UnitZ();
    int rays_per_side = 16;  ///< per lenslet: each lenslet's brightness is quantised by its rays
};

/// A photograph of page `page` of `sheet`, mounted in `design` as `scene` says, printed with
/// `printer`'s tone (its full ink is the lines' transmittance): linear, one channel, as
/// calibrate::photograph. InputError for a design that is not Design I or II; the camera must
/// see the sheet's printed side (not from_back).
Image simulated_moire_photo(const optics::Design& design, const print::MoireSheet& sheet,
                            const print::PrinterProfile& printer, const MoireScene& scene, const Camera& camera,
                            int page = 0);

}  // namespace rfd::calibrate
