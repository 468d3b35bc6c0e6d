#pragma once
// Spot analysis of a plain lens system at one field angle: where the exact chief ray lands
// in the paraxial focal plane compared with the paraxial prediction, and the RMS spot.

#include <array>
#include <cstddef>
#include <limits>
#include <optional>
#include <vector>

#include "core/options.hpp"
#include "optics/exact.hpp"
#include "optics/system.hpp"

namespace rfd::optics {

struct SpotReport {
    double field_angle_deg = 0.0;
    double pupil_semi_diameter = 0.0;  ///< mm, at the first vertex plane
    std::size_t rays_traced = 0;
    double focal_plane_z = 0.0;        ///< paraxial rear focal plane, mm
    /// y of the exact chief ray in that plane, mm; none when the chief ray does not get there
    /// (stopped: chief_status says why; or Ok but leaving parallel to the plane).
    std::optional<double> chief_height_exact;
    double chief_height_paraxial = 0.0;
    RayStatus chief_status = RayStatus::Ok;
    /// mm, about the centroid of the rays that reached the plane; none when none did.
    std::optional<double> rms_spot_radius;
    std::optional<double> centroid_y;  ///< mm
    std::array<std::size_t, kRayStatusCount> status_counts{};
};

/// The rays of `rfd optics trace`: about this many over the pupil.
inline constexpr IntegerOption kPupilRaysOption{"--pupil-rays", "", "", 1, 10000000, 1001,
                                                "Rays across the pupil (a square grid clipped to a disc)", "--rays"};

/// Traces a square grid of about `rays` rays clipped to the pupil disc (grid points on the
/// rim, within kApertureTolerance, included, so the grid keeps its symmetry), all at the
/// field angle (in the y-z plane), from the first vertex plane. `pupil_semi_diameter` <= 0 takes
/// the first surface's clear aperture. Throws InputError for an afocal system or a first
/// surface without a circular aperture when no pupil is given.
SpotReport spot_report(const SequentialSystem& system, double field_angle_deg,
                       double pupil_semi_diameter, int rays);

/// Centroid and RMS radius about it of a set of spot points (two passes, so that a spot
/// of micrometres far off the axis keeps its digits). NaN for an empty set.
struct SpotStatistics {
    Eigen::Vector2d centroid = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
    double rms_radius = std::numeric_limits<double>::quiet_NaN();
};
SpotStatistics spot_statistics(const std::vector<Eigen::Vector2d>& points);

/// Propagates a ray in a straight line to the plane z.
Eigen::Vector3d point_at_z(const Ray& ray, double z);

}  // namespace rfd::optics
