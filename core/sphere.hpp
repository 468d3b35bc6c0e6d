#pragma once
// Directions on the unit sphere, as reflectance fields and displays use them.
//
// Frame of a reflectance field: x to the right and y up in the image, z toward the camera
// (right-handed). A light direction is the unit vector from the object toward the light, so
// the hemisphere the light stage covers is z > 0 (the RTI convention of .lp files).
// Spherical angles: theta is the polar angle from +z (0 at the pole, 90 degrees on the
// horizon, 180 at the guardian point below it), phi the azimuth from +x toward +y.
// Internally radians; files and the command line use degrees.
//
// Example: Eigen::Vector3d d = direction_from_angles(degrees_to_radians(30), 0.0);

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rfd {

/// Spherical angles of a direction, radians.
struct SphericalAngles {
    double theta = 0.0;  ///< polar angle from +z, [0, pi]
    double phi = 0.0;    ///< azimuth from +x toward +y, (-pi, pi]
};

inline Eigen::Vector3d direction_from_angles(double theta, double phi) {
    const double s = std::sin(theta);
    return {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
}

/// Angles of a (not necessarily unit) non-zero vector.
inline SphericalAngles angles_of(const Eigen::Vector3d& d) {
    const double r = d.norm();
    return {std::acos(std::clamp(d.z() / r, -1.0, 1.0)), std::atan2(d.y(), d.x())};
}

/// Angle between two unit vectors, radians; accurate for tiny and near-pi angles alike.
inline double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::atan2(a.cross(b).norm(), a.dot(b));
}

/// `count` near-uniform upper-hemisphere directions on a Fibonacci spiral (equal area per
/// point, z in (0, 1)): a quick, deterministic set for tests, benchmarks and probes.
inline std::vector<Eigen::Vector3d> fibonacci_hemisphere(std::size_t count) {
    std::vector<Eigen::Vector3d> directions;
    const double golden_angle = std::numbers::pi * (3.0 - std::sqrt(5.0));
    for (std::size_t i = 0; i < count; ++i) {
        const double z = 1.0 - (static_cast<double>(i) + 0.5) / static_cast<double>(count);
        const double r = std::sqrt(1.0 - z * z), phi = golden_angle * static_cast<double>(i);
        directions.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
    }
    return directions;
}

}  // namespace rfd
