#pragma once
// Interpolation of a reflectance field between its light directions (thesis 4.4).
//
// A novel light direction d is rendered as a non-negative combination of at most three
// measured images, R(d) ~ sum_i l_i(d) R_i (eq. 4.1), with weights that are local, sum to one,
// give weight 1 to a measured direction and change continuously with d.
//
// Triangulation (4.4): a CGAL Delaunay tetrahedralisation of the directions D plus a guardian
// point g at the theta = pi pole. Its hull facets that do not touch g form the triangulation
// T; the vertices sharing a hull edge with g are the boundary vertices, sorted by phi (the
// tetrahedralisation of cospherical points also links g to vertices through the inside). Triangles
// are oriented det(a, b, c) > 0 (counter-clockwise seen from outside the sphere) and listed
// in canonical_order.
//
// Weights inside a triangle (a, b, c) of T: l_a = det(d, b, c) / S, l_b = det(a, d, c) / S,
// l_c = det(a, b, d) / S, S the sum of the three: the barycentric coordinates of the point
// where the ray d meets the flat hull triangle. Eq. 4.6 uses ratios of spherical solid
// angles instead; those are NOT continuous across an edge (on a shared edge the ratio
// depends on the opposite vertex: 0.780 vs 0.784 at a quarter of an edge of 60-degree
// triangles, see tests/test_interpolation.cpp), while the coordinates above are (on an
// edge they depend on its two ends only). spherical_triangle_solid_angle() is kept for that
// comparison and for callers that need solid angles.
//
// Outside T (near the horizon) the arc interpolation of eq. 4.7/4.8 between the boundary
// vertices b_j, b_k that bracket phi (wrap-around included), made continuous with T: the
// weights are the ones of the boundary edge (b_j, b_k) at the point of the edge with d's
// azimuth, l_j proportional to cross(d_xy, b_k,xy), l_k to cross(b_j,xy, d_xy). Where an
// azimuth gap between consecutive boundary vertices reaches 180 degrees (a direction set
// that does not surround the zenith) those weights are undefined and eq. 4.8 is used as
// written (linear in phi; continuous in phi, but not with T).
//
// Nearest: weight 1 on the closest direction (ties: lowest index), the baseline.
//
// Input directions: unit vectors toward the light in the field frame (core/sphere.hpp).
// Directions up to 5 degrees below the horizon are accepted (calibration noise of a real
// stage); lower ones, fewer than three, non-finite ones, duplicates (closer than 1e-6 rad)
// and sets that lie on one plane with the guardian are InputError.
// Point location is a lat-long grid of cells, each listing the triangles and the directions
// that may be found from a query in it: a query costs one cell lookup and a few tests.
//
// Example: SphericalInterpolator interp(field.directions);
//          InterpolationWeights w = interp.weights(direction_from_angles(0.3, 1.0));

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "core/names.hpp"

#include "relight/adaptive.hpp"

namespace rfd::relight {

/// delaunay: the barycentric coordinates above (continuous); solid_angle: eq. 4.6 as the
/// thesis writes it, l_a = Omega(d, b, c) / (Omega(d, b, c) + Omega(a, d, c) + Omega(a, b, d)),
/// same triangles and horizon band (tiny jumps across edges); nearest: the baseline.
enum class Interpolation { Delaunay, SolidAngle, Nearest };
/// As the command line and a pattern's rfd:interpolation attribute spell them.
inline constexpr std::array kInterpolationNames{Named{Interpolation::Delaunay, "delaunay"},
                                                Named{Interpolation::SolidAngle, "solid-angle"},
                                                Named{Interpolation::Nearest, "nearest"}};

/// Weights of at most three directions; entries past `count` are unused (index 0, weight 0).
struct InterpolationWeights {
    std::array<std::size_t, 3> index{};  ///< direction indices
    std::array<double, 3> weight{};      ///< >= 0, sum 1 over the first `count`
    std::size_t count = 0;
};

/// Solid angle (steradians, >= 0) of the spherical triangle of three unit vectors, by the
/// formula of Van Oosterom and Strackee (1983): tan(Omega/2) = |det(a,b,c)| /
/// (1 + a.b + b.c + c.a), accurate for tiny and near-hemispherical triangles alike.
double spherical_triangle_solid_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                      const Eigen::Vector3d& c);

class SphericalInterpolator {
public:
    /// Triangulates `directions` (normalised here). Throws InputError as described above.
    explicit SphericalInterpolator(std::vector<Eigen::Vector3d> directions);
    ~SphericalInterpolator();
    SphericalInterpolator(SphericalInterpolator&&) noexcept;
    SphericalInterpolator& operator=(SphericalInterpolator&&) noexcept;

    /// l_i(direction) for a unit `direction` anywhere on the sphere. Thread-safe.
    InterpolationWeights weights(const Eigen::Vector3d& direction,
                                 Interpolation method = Interpolation::Delaunay) const;
    /// The same, trying triangle `hint` first (then walking to its neighbours for a few
    /// steps) and leaving in it the triangle found
    /// (kNoTriangle outside T): coherent queries, such as neighbouring print dots, then
    /// skip the point location. The same weights as without a hint (on an edge shared by two
    /// triangles, up to rounding). `direction` need not be unit here: any positive multiple
    /// gives the same weights.
    static constexpr std::size_t kNoTriangle = static_cast<std::size_t>(-1);
    InterpolationWeights weights(const Eigen::Vector3d& direction, Interpolation method, std::size_t& hint) const;

    /// True when `direction` lies in a triangle of T: the interpolation there blends measured
    /// lights rather than extrapolating along the horizon band's arcs.
    bool covers(const Eigen::Vector3d& direction) const {
        return weights(direction, Interpolation::Delaunay).count == 3;
    }
    std::size_t size() const { return directions_.size(); }
    const std::vector<Eigen::Vector3d>& directions() const { return directions_; }
    /// T, canonical_order'ed, det(a, b, c) > 0.
    const std::vector<Triangle>& triangles() const { return triangles_; }
    /// Vertices sharing a hull edge with the guardian, by ascending phi (ties: index).
    const std::vector<std::size_t>& boundary_vertices() const { return boundary_; }
    /// One-ring neighbours of every direction in T.
    std::vector<std::vector<std::size_t>> one_rings() const;

    /// Triangle t's three edge planes: inside it d . planes[j] >= 0 for every j, and the weight
    /// of its vertex j is d . planes[j] over the sum of the three (see in_triangle).
    const std::array<Eigen::Vector3d, 3>& edge_planes(std::size_t t) const { return planes_[t]; }

    /// The weights of triangle `t` at d (any positive multiple of a direction) when d lies in
    /// it; false otherwise. Inline: the pattern encoder calls it once per print dot.
    bool in_triangle(const Eigen::Vector3d& d, std::size_t t, InterpolationWeights& out) const {
        const auto& planes = planes_[t];
        std::array<double, 3> w{};
        bool inside = true;
        for (std::size_t j = 0; j < 3; ++j) {
            w[j] = d.dot(planes[j]);
            inside = inside && w[j] >= -kInsideTolerance;
        }
        if (!inside) return false;
        for (double& v : w) v = v > 0.0 ? v : 0.0;
        double sum = w[0] + w[1] + w[2];
        if (!(sum > 0.0)) return false;  // the antipodal cone of a triangle
        // Rounding-size weights (a query at a vertex or on an edge) become exact zeros, so a
        // measured direction reproduces its image bit for bit.
        for (double& v : w)
            if (v < 1e-12 * sum) v = 0.0;
        sum = w[0] + w[1] + w[2];
        out.count = 3;
        for (std::size_t j = 0; j < 3; ++j) {
            out.index[j] = triangles_[t][j];
            out.weight[j] = w[j] / sum;
        }
        return true;
    }

private:
    static constexpr double kInsideTolerance = 1e-14;
    struct Grid;
    bool locate(const Eigen::Vector3d& d, std::size_t cell, InterpolationWeights& out,
                std::size_t* found = nullptr) const;
    InterpolationWeights arc_weights(const Eigen::Vector3d& d) const;
    InterpolationWeights nearest_weights(const Eigen::Vector3d& d, std::size_t cell) const;

    std::vector<Eigen::Vector3d> directions_;
    std::vector<Triangle> triangles_;
    // Per triangle, the edge normals whose dot products with d give its weights.
    std::vector<std::array<Eigen::Vector3d, 3>> planes_;
    // Per triangle, the triangle across the edge opposite vertex j (kNoTriangle at the rim).
    std::vector<std::array<std::size_t, 3>> neighbours_;
    std::vector<std::size_t> boundary_;
    std::vector<double> boundary_phi_;
    std::unique_ptr<Grid> grid_;
};

/// The interpolation triangulation T of `directions` (a Triangulate for adaptive capture).
std::vector<Triangle> delaunay_triangles(const std::vector<Eigen::Vector3d>& directions);

}  // namespace rfd::relight
