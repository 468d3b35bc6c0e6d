#pragma once
// What the preview page shows: for a set of light directions over the display's range, the
// predicted display and the field relit in software (the reference of compare.hpp), at the
// display's resolution, plus what the page needs to blend between them as rfd does (the
// directions' triangulation and edge planes, relight/interpolation.hpp) and to mark the
// field of view and the crosstalk onset on its light control.
//
// Directions are in the display's frame, toward the light (predict/display_lights.hpp): z
// is the display's axis, as the page's light disc is.
//
// Example: PreviewSet set = preview_set(simulator, comparison, mapping, 96, degrees_to_radians(12), options);

#include <array>
#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "core/options.hpp"
#include "core/image.hpp"
#include "optics/display.hpp"
#include "patterns/encode.hpp"
#include "predict/compare.hpp"

namespace rfd::predict {

/// Where the display stops along one azimuth (display frame).
struct PreviewRim {
    double phi_deg = 0.0;
    std::optional<double> wrap_over_deg;   ///< the field of view's edge
    std::optional<double> crosstalk_deg;   ///< the crosstalk onset
};

/// How many light directions the preview page precomputes (`simulate preview --count`, a
/// project's preview_lights, where 0 turns the light control off).
inline constexpr IntegerOption kPreviewLightsOption{"--count", "preview_lights", "", 3, 1024, 96,
                                                    "Light directions of the preview page (a project's 0 leaves the page without a light "
                                                    "control)"};

struct PreviewSet {
    std::vector<Eigen::Vector3d> directions;  ///< display frame, toward the light, unit
    std::vector<Image> predicted, relit;      ///< per lenslet (whole cells), 3 channels, times `scale`
    /// The predicted pictures of a second pattern of the same field (the direct encoding
    /// beside an optimised one), same directions and scale; empty when there is none.
    std::vector<Image> predicted_direct;
    double scale = 1.0;                       ///< the compared values times this: the brightest relit value is 1
    double max_angle_deg = 0.0;               ///< the cone the directions cover
    std::vector<std::array<std::size_t, 3>> triangles;         ///< of the directions' triangulation
    std::vector<std::array<Eigen::Vector3d, 3>> edge_planes;   ///< weights: d . plane_j over their sum
    std::vector<PreviewRim> rims;             ///< every 15 degrees of azimuth
};

/// Predicts and relights `count` directions over the cone of `max_angle_rad` about the
/// display's axis (cone_directions, seed 1). `options` are the simulation's. With `direct`
/// (the same field's direct encoding, beside an optimised pattern), its predictions too.
PreviewSet preview_set(const optics::DisplaySimulator& simulator, const DisplayComparison& comparison,
                       const patterns::AngularMapping& mapping, std::size_t count, double max_angle_rad,
                       const optics::SimulationOptions& options, const DisplayComparison* direct = nullptr);

}  // namespace rfd::predict
