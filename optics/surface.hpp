#pragma once
// Optical surfaces: a profile (flat or conic), an aperture, and the medium behind it.
//
// Frame: right-handed, millimetres. z is the optical axis and points the way light travels,
// from the light source (behind the display) toward the observer; x is to the right and
// y up as seen by the observer. A surface's vertex lies at (0, 0, z) or, for an arrayed
// surface, at (cx, cy, z) for every lenslet centre (cx, cy) of its lattice.
//
// Conic profile, in the vertex frame with r^2 = x^2 + y^2 and curvature c = 1/R:
//     sag(r) = c r^2 / (1 + sqrt(1 - (1 + k) c^2 r^2))
// k = 0 sphere, -1 < k < 0 prolate ellipsoid, k = -1 paraboloid, k < -1 hyperboloid,
// k > 0 oblate ellipsoid. c > 0 puts the centre of curvature on the +z side (a surface
// convex toward the incoming light). Only the "vertex branch" (the sheet through the
// vertex) is part of the surface.

#include <cstdint>
#include <optional>
#include <string>
#include <variant>

#include <Eigen/Core>

#include "optics/lattice.hpp"

namespace rfd::optics {

/// A plane perpendicular to the axis.
struct Flat {};

/// A conic of revolution; a sphere when conic_constant == 0.
struct Conic {
    double curvature = 0.0;       ///< 1/R in 1/mm; sign as in the header comment
    double conic_constant = 0.0;  ///< k (Schwarzschild constant)
};

using Profile = std::variant<Flat, Conic>;

/// A round clear aperture centred on the axis.
struct CircularAperture {
    double semi_diameter = 0.0;  ///< mm
};

/// An arrayed surface: one copy of the profile per lattice cell, clipped to the cell,
/// with its vertex at the cell centre. The array's outer boundary is its aperture.
struct LatticeAperture {
    Lattice lattice;
};

/// A surface without aperture limit (e.g. a large sheet or a bookkeeping plane).
struct Unbounded {};

using Aperture = std::variant<CircularAperture, LatticeAperture, Unbounded>;

/// Relative tolerance on aperture tests: a hit at radius r passes a semi-diameter s when
/// r <= s * (1 + kApertureTolerance). It absorbs rounding on rays aimed exactly at the
/// rim (a marginal ray traced at the full semi-diameter is in, not vignetted).
inline constexpr double kApertureTolerance = 1e-9;

/// One refracting (or bookkeeping) surface of a sequential system.
struct Surface {
    Profile profile = Flat{};
    Aperture aperture = Unbounded{};
    double z = 0.0;            ///< vertex position along the axis, mm
    double index_after = 1.0;  ///< refractive index of the medium behind (z greater than) it
    std::string label;         ///< e.g. "A front", "B pattern"; for reports only
};

/// Curvature of a profile (0 for flat).
double curvature_of(const Profile& profile);
/// Conic constant (0 for flat).
double conic_of(const Profile& profile);
/// Sag at radial distance squared r2 from the vertex; nullopt where the conic does not
/// reach (1 - (1+k) c^2 r^2 < 0).
std::optional<double> sag(const Profile& profile, double r2);
/// Outward unit normal (pointing toward +z at the vertex) at local point p on the profile.
Eigen::Vector3d normal_at(const Profile& profile, const Eigen::Vector3d& local_point);

/// A ray that starts on a curved surface it has just crossed must not meet it again at its
/// own starting point: with t_min >= 0 no hit closer than this (mm) along the ray is reported.
inline constexpr double kSelfIntersection = 1e-9;

/// Distance t along a ray (origin o, unit direction d, both in the vertex frame) to the
/// first intersection with the vertex branch of the profile with t > t_min, computed with
/// the cancellation-free form of the quadratic root. nullopt when the ray misses.
/// t_min >= 0: the ray may be leaving this surface; a conic's hits closer than
/// kSelfIntersection are not reported. t_min < 0: the ray has not crossed this surface
/// yet but may already be on it (where it touches the surface just crossed, e.g. two lenses
/// whose vertices touch); a hit at |t| <= kSelfIntersection is then reported when the ray
/// crosses from the front (the side the vertex normal points away from) to the back, and a
/// flat's hit down to t_min in any case.
std::optional<double> intersect(const Profile& profile, const Eigen::Vector3d& o,
                                const Eigen::Vector3d& d, double t_min);

/// Refraction by Snell's law. `d` is the unit incident direction, `n` the unit normal
/// (either orientation), eta = n_before / n_after. Returns the unit refracted direction,
/// or nullopt on total internal reflection.
std::optional<Eigen::Vector3d> refract(const Eigen::Vector3d& d, const Eigen::Vector3d& n,
                                       double eta);

/// Power transmittance of an uncoated interface for unpolarised light (the mean of the
/// s and p Fresnel transmittances), from the cosines of the angles of incidence and
/// refraction. At normal incidence 1 - ((n1 - n2) / (n1 + n2))^2, 0.958 for glass in air.
double fresnel_transmittance(double cos_i, double cos_t, double n1, double n2);

}  // namespace rfd::optics
