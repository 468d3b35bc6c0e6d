#pragma once
// The light a holder must let through: rays of the design's full field of view, traced
// exactly (optics/exact.hpp) from the holder's front face through every surface, kept
// only when they pass every clear aperture the holder leaves. The generator sizes the
// holder's channels from their envelope; the beam-clearance check tests them against the
// printed mesh.
//
// Field of view: the cone of incident directions up to the exact wrap-over angle along x
// and y (optics::wrap_over_angle: Designs I/II, a lenslet's chief ray leaving its cell;
// III/IV, the main lens's chief ray leaving the meso-pixel array), sampled on the axis and
// at half and 98 % of that angle in `azimuths` directions.
// Frame and units: the design's (holders/holder.hpp).

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "holders/holder.hpp"
#include "optics/design.hpp"

namespace rfd::holders {

struct BeamPath {
    std::vector<Eigen::Vector3d> points;  ///< front face, every surface met, then the exit (if asked)
    Eigen::Vector2d cell_centre = Eigen::Vector2d::Zero();  ///< centre of the lenslet entered (I/II)
};

struct BeamSampling {
    int rays_per_side = 7;  ///< entry grid over a lenslet (I/II) or the main lens (III/IV)
    int azimuths = 8;       ///< directions around each cone
};

/// Half-angle of the incident cone the design accepts, degrees: the smaller exact wrap-over
/// angle along x and y.
double field_of_view_half_deg(const optics::Design& design);

/// Rays of the full field of view that pass every clear aperture in `apertures` (planes
/// without one are unbounded), from z_front to the last surface, then on to z_exit if
/// given. Designs I/II trace through the lenslets at the array's corners, edges and centre.
std::vector<BeamPath> beam_paths(const optics::Design& design, const std::vector<ClearAperture>& apertures,
                                 double z_front, std::optional<double> z_exit, const BeamSampling& sampling = {});

/// Largest |x|, |y| of the paths at z, absolute or relative to each path's lenslet centre.
struct Envelope {
    double x = 0.0, y = 0.0, r = 0.0;
    bool empty = true;
};
Envelope envelope_at(const std::vector<BeamPath>& paths, double z, bool relative_to_cell);
/// The envelope's maximum over [z0, z1], exact: the largest over every z in the interval.
Envelope envelope_over(const std::vector<BeamPath>& paths, double z0, double z1, bool relative_to_cell);

}  // namespace rfd::holders
