#pragma once
// rfd's own photographs of an assembled display, for trying `rfd calibrate registration`
// without a printer: the printed pattern mounted on the lens array with a known error (shift,
// turn, pitch: optics/misalignment.hpp), lit from behind by a distant light, photographed from
// the front. The diffuser shows what the display's own forward model says
// (optics::DisplaySimulator, the exact tracer); around it the holder is dark. The diffuser is
// what the camera sees, so no parallax is drawn: the picture is the diffuser's plane.
//
// Frames: the array's (optics/display.hpp: mm, origin on the axis, y up as the camera sees it)
// and the photographed plane's (calibrate/camera.hpp: mm, y down), a rectangle `display_paper`
// holding the array and its holder, the axis at its middle:
//     plane = middle + F a,   F = diag(1, -1).
//
// Example: optics::MisalignedTransparency mounted(printed, {{0.05, 0.0}, 0.0, 0.0});
//          Image photo = simulated_display_photo(design, mounted, {}, framing_camera(display_paper(design)));

#include <Eigen/Core>

#include "calibrate/camera.hpp"
#include "core/image.hpp"
#include "optics/design.hpp"
#include "optics/display.hpp"
#include "print/moire.hpp"
#include "print/printer.hpp"

namespace rfd::calibrate {

/// The plane the photograph of the assembled display shows: the array's bounding box and
/// kHolderMm of holder on every side.
inline constexpr double kHolderMm = 15.0;
print::Paper display_paper(const optics::Design& design);

/// The point of the photographed plane where array point `a` lies.
Eigen::Vector2d display_plane_point(const optics::Design& design, const Eigen::Vector2d& a);

/// The diffuser image at array point `a`: the mean of its channels, bilinear; NaN outside it.
double diffuser_at(const optics::DiffuserImage& diffuser, const Eigen::Vector2d& a);

/// What is photographed besides the pattern: the light and how much light the holder passes.
struct DisplayScene {
    /// The light's direction of travel, from behind toward the camera (z > 0, the display's
    /// frame).
    Eigen::Vector3d light = Eigen::Vector3d::UnitZ();
    double light_radius_rad = print::kSunRadius;  ///< the sun's disc
    double holder = 0.02;               ///< the holder's brightness over bare diffuser's
    int rays_per_side = 12;             ///< per lenslet
};

/// A photograph of `design` assembled with `mounted` (the printed pattern as it sits on the
/// array, its transmittance) in the light of `scene`: linear, one channel (the mean of the
/// pattern's channels), as calibrate::photograph. InputError for a design that is not Design I
/// or II; the camera must look at the front (not from_back).
Image simulated_display_photo(const optics::Design& design, const optics::Transparency& mounted,
                              const DisplayScene& scene, const Camera& camera);

}  // namespace rfd::calibrate
