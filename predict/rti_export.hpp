#pragma once
// What a display will show, as a reflectance field: one predicted picture per light
// direction, so the tools of the field (CNR relight, RTIBuilder's viewers) can open a
// display before it is printed, as they open a capture.
//
// Directions are in the display's frame (predict/display_lights.hpp: toward the light,
// z the display's axis), spread over a cone about the axis: the directions the display is
// made for, not the whole hemisphere, most of which it shows as wrap-over.
//
// Example: auto lights = cone_directions(64, degrees_to_radians(10.0), 1);
//          relight::ReflectanceField shown = predicted_field(simulator, printed, lights, {}, true);
//          relight::write_field("out/rti", shown, "display", ".jpg");

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "optics/display.hpp"
#include "relight/field.hpp"

namespace rfd::predict {

/// `count` unit directions toward the light over the cone of `half_angle_rad` about +z:
/// relight::repulsion_pattern's near-uniform hemisphere, its polar angles scaled into the
/// cone. Deterministic for (count, half angle, seed).
std::vector<Eigen::Vector3d> cone_directions(std::size_t count, double half_angle_rad, std::uint64_t seed);

/// The display's picture under a white light from each of `toward_lights` (display frame,
/// toward the light), as a field with those directions: the diffuser image, or with
/// `per_lenslet` one value per lenslet. InputError for a light from the front.
relight::ReflectanceField predicted_field(const optics::DisplaySimulator& simulator, const optics::Transparency& pattern,
                                          const std::vector<Eigen::Vector3d>& toward_lights,
                                          const optics::SimulationOptions& options, bool per_lenslet);

}  // namespace rfd::predict
