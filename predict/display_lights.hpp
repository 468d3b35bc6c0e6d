#pragma once
// The lights a user names in the field's frame (core/sphere.hpp: z toward the camera,
// direction toward the light), as a display encoded with an AngularMapping meets them:
// optics::DisplayLight in the display's frame (direction of travel, z > 0 from behind).
// A light at field direction L shows on the display what the field shows under L, so the
// display direction is mapping.display_direction(L); a disc's radius shrinks by the
// mapping's angle scale.
//
// Environment maps. A latitude-longitude map of radiance in the field's frame (the
// convention of relight::EnvironmentMap: row 0 at the zenith +z, column W/2 facing +x, phi
// growing toward +y) becomes one point light per pixel: irradiance = radiance x the
// pixel's solid angle, from a direction inside the pixel (a low-discrepancy point in its
// cos(theta) x phi rectangle, so neighbouring pixels' directions do not line up), mapped to
// the display. Pixels whose light meets the display from the front are dropped (counted);
// black pixels cost nothing.
// No finer than needed: the display resolves directions no finer than one print dot on
// the pattern plane (angle dot / B), and a simulation gives each direction at least one
// ray per lenslet; so the map is box-filtered (power-weighted, 2 x 2 at a time) while its
// pixels are smaller than that angle (in the field's frame) or while more pixels carry
// light from behind than `max_directions`.
//
// Example: auto lights = environment_lights(read_image("sky.exr"), mapping, 0.003, 1024, &report);

#include <cstddef>
#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/options.hpp"
#include "core/image.hpp"
#include "core/names.hpp"
#include "optics/display.hpp"
#include "patterns/encode.hpp"
#include "relight/render.hpp"

namespace rfd::predict {

using patterns::AngularMapping;

/// The frame a user names a light's direction in (THETA,PHI toward the light):
///  - Display: z is the display's axis, x and y the field's at zero tilt and turn; 0,0 is a
///    lamp straight behind the display, and THETA is the angle to its axis.
///  - Field: the field's frame (core/sphere.hpp), as the field was captured or rendered.
/// The two agree for a pattern encoded without --tilt, --turn or --angle-scale.
enum class LightFrame { Display, Field };
inline constexpr std::array kLightFrameNames{Named{LightFrame::Display, "display"}, Named{LightFrame::Field, "field"}};
/// The frame --light is named in unless --frame says otherwise, every command's.
inline constexpr LightFrame kDefaultLightFrame = LightFrame::Display;

/// The direction of travel of light from `toward` (display frame, toward the light), and
/// back: x and y reversed, z kept.
inline Eigen::Vector3d travel_from(const Eigen::Vector3d& toward) { return {-toward.x(), -toward.y(), toward.z()}; }

/// `light`, named in `frame`, in the field's frame (unchanged for LightFrame::Field). A
/// display-frame light at THETA,PHI is the field light that the display meets along
/// incident direction (-sin THETA cos PHI, -sin THETA sin PHI, cos THETA); a disc keeps its
/// angular radius on the display. An environment map is refused (InputError).
relight::Light light_in_field_frame(const relight::Light& light, LightFrame frame, const AngularMapping& mapping);

/// Where a light meets a display, in both frames, and whether the display shows it cleanly:
/// the wrap-over angle (the field of view's edge) and the crosstalk onset along the light's
/// own azimuth, exact model (optics/analysis.hpp).
struct LightCheck {
    double display_theta_deg = 0, display_phi_deg = 0;  ///< toward the light; theta: angle to the axis
    double field_theta_deg = 0, field_phi_deg = 0;
    std::optional<double> wrap_over_deg;   ///< nullopt: none up to kWrapOverSearchLimitDeg
    std::optional<double> crosstalk_deg;   ///< nullopt: none up to the same limit
    bool from_front = false;               ///< the light meets the display from the front

    bool outside_field_of_view() const { return from_front || (wrap_over_deg && display_theta_deg >= *wrap_over_deg); }
    bool beyond_crosstalk_onset() const { return crosstalk_deg && display_theta_deg >= *crosstalk_deg; }
    /// What is wrong, naming the angles ("" when nothing is), e.g. "25.0 deg from the
    /// display's axis, outside its field of view (wrap-over at 21.8 deg along this azimuth)".
    std::string warning() const;
};
LightCheck check_light(const optics::DesignOptics& optics, const optics::DisplayLight& light,
                       const AngularMapping& mapping);

/// A directional or disc light of the field's frame, for the display. An environment map
/// is refused (InputError): use environment_lights().
optics::DisplayLight display_light(const relight::Light& light, const AngularMapping& mapping);

/// How an environment map was sampled.
struct EnvironmentSampling {
    int width = 0, height = 0;                 ///< the map as given
    int sampled_width = 0, sampled_height = 0; ///< after box filtering
    int reduction = 1;                         ///< box filter size per side
    std::string reason;                        ///< why it was filtered ("" when not)
    std::size_t directions = 0;                ///< lights made: pixels lighting the display from behind
    std::size_t in_front = 0;                  ///< pixels with light that meets the display from the front
};

/// Checks `radiance` (2:1, 1 or 3 channels, every sample finite and >= 0; InputError
/// naming `name`, the pixel and the channel otherwise) and turns it into point lights, see
/// above. `resolution_rad` is the display's finest angle in the field's frame; 0 means any.
std::vector<optics::DisplayLight> environment_lights(const Image& radiance, const std::string& name,
                                                     const AngularMapping& mapping, double resolution_rad,
                                                     std::size_t max_directions, EnvironmentSampling* report = nullptr);

/// The same for any field-to-display mapping of directions (unit toward the light in, unit
/// direction of travel out; z <= 0 out means the light meets the display from the front),
/// e.g. Designs III/IV's patterns::field_light_of.
using FieldToDisplay = std::function<Eigen::Vector3d(const Eigen::Vector3d&)>;
std::vector<optics::DisplayLight> environment_lights(const Image& radiance, const std::string& name,
                                                     const FieldToDisplay& to_display, double resolution_rad,
                                                     std::size_t max_directions, EnvironmentSampling* report = nullptr);

/// The display's finest resolved angle in the field's frame: one print dot on the pattern
/// plane seen from the lenslet (dot / B), times the mapping's angle scale.
double display_resolution_rad(const optics::DesignOptics& optics, const AngularMapping& mapping);

}  // namespace rfd::predict
