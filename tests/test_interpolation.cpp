// Spherical interpolation (thesis 4.4): the triangulation against an independent convex hull,
// the weight properties of 4.4 over random direction sets, and the degenerate inputs.

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/interpolation.hpp"
#include "tests/support/hull_triangles.hpp"

namespace rfd::relight {
namespace {

std::vector<Eigen::Vector3d> random_hemisphere(std::size_t count, std::uint64_t seed) {
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<Eigen::Vector3d> directions;
    for (std::size_t i = 0; i < count; ++i) {
        const double z = unit(random), phi = 2.0 * kPi * unit(random);
        const double r = std::sqrt(1.0 - z * z);
        directions.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
    }
    return directions;
}

// theta rings x phi columns plus the zenith: every quad of the grid is cocircular.
std::vector<Eigen::Vector3d> regular_grid(int rings, int columns, double lowest_theta) {
    std::vector<Eigen::Vector3d> directions{Eigen::Vector3d::UnitZ()};
    for (int r = 1; r <= rings; ++r)
        for (int c = 0; c < columns; ++c)
            directions.push_back(direction_from_angles(lowest_theta * r / rings, 2.0 * kPi * c / columns));
    return directions;
}

std::vector<double> dense(const InterpolationWeights& w, std::size_t n) {
    std::vector<double> out(n, 0.0);
    for (std::size_t k = 0; k < w.count; ++k) out[w.index[k]] += w.weight[k];
    return out;
}

double max_difference(const std::vector<double>& a, const std::vector<double>& b) {
    double worst = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::abs(a[i] - b[i]));
    return worst;
}

void expect_partition_of_unity(const InterpolationWeights& w, std::size_t n) {
    ASSERT_GE(w.count, 1u);
    ASSERT_LE(w.count, 3u);
    double sum = 0.0;
    for (std::size_t k = 0; k < w.count; ++k) {
        EXPECT_LT(w.index[k], n);
        EXPECT_GE(w.weight[k], 0.0);
        sum += w.weight[k];
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
}

std::set<Triangle> as_sorted_set(const std::vector<Triangle>& triangles) {
    std::set<Triangle> out;
    for (Triangle t : triangles) {
        std::sort(t.begin(), t.end());
        out.insert(t);
    }
    return out;
}

// The triangulation computed independently (tests/support/hull_triangles.hpp).
std::set<Triangle> hull_reference(const std::vector<Eigen::Vector3d>& directions) {
    return as_sorted_set(rfd::testing::hull_triangles(directions));
}

TEST(Interpolation, TrianglesAreTheHullOfDirectionsAndGuardian) {
    for (const std::uint64_t seed : {1u, 2u, 3u}) {
        const auto directions = random_hemisphere(80, seed);
        const SphericalInterpolator interp(directions);
        EXPECT_EQ(as_sorted_set(interp.triangles()), hull_reference(directions));
        // Euler: a hull of n + 1 points in convex position has 2(n + 1) - 4 faces, of which
        // the guardian's fan has one per boundary vertex.
        EXPECT_EQ(interp.triangles().size(), 2 * (directions.size() + 1) - 4 - interp.boundary_vertices().size());
        EXPECT_EQ(delaunay_triangles(directions), interp.triangles());
        EXPECT_EQ(canonical_order(interp.triangles()), interp.triangles());
        for (const Triangle& t : interp.triangles())
            EXPECT_GT(directions[t[0]].dot(directions[t[1]].cross(directions[t[2]])), 0.0);
    }
}

TEST(Interpolation, BoundaryVerticesAreSortedByPhiAndLowest) {
    const auto directions = random_hemisphere(120, 7);
    const SphericalInterpolator interp(directions);
    const auto& boundary = interp.boundary_vertices();
    ASSERT_GE(boundary.size(), 3u);
    for (std::size_t k = 1; k < boundary.size(); ++k)
        EXPECT_LE(angles_of(directions[boundary[k - 1]]).phi, angles_of(directions[boundary[k]]).phi);
    // The lowest direction always sees the guardian.
    const auto lowest = std::min_element(directions.begin(), directions.end(),
                                         [](const auto& a, const auto& b) { return a.z() < b.z(); });
    EXPECT_NE(std::find(boundary.begin(), boundary.end(), static_cast<std::size_t>(lowest - directions.begin())),
              boundary.end());
    const auto rings = interp.one_rings();
    ASSERT_EQ(rings.size(), directions.size());
    for (const auto& ring : rings) EXPECT_GE(ring.size(), 2u);
}

TEST(Interpolation, WeightsArePartitionOfUnityAndReproduceTheDirection) {
    const auto directions = random_hemisphere(100, 11);
    const SphericalInterpolator interp(directions);
    const auto triangles = interp.triangles();
    std::mt19937_64 random(5);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int q = 0; q < 4000; ++q) {
        // Whole sphere: the weights are defined everywhere.
        const double z = 2.0 * unit(random) - 1.0, phi = 2.0 * kPi * unit(random);
        const Eigen::Vector3d d(std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z);
        const auto w = interp.weights(d);
        expect_partition_of_unity(w, directions.size());
        // Brute force: is d inside the cone of some triangle of T?
        bool inside_some = false;
        for (const Triangle& t : triangles) {
            const auto &a = directions[t[0]], &b = directions[t[1]], &c = directions[t[2]];
            if (d.dot(b.cross(c)) > 1e-9 && d.dot(c.cross(a)) > 1e-9 && d.dot(a.cross(b)) > 1e-9) inside_some = true;
        }
        EXPECT_EQ(w.count == 3, inside_some) << "query " << d.transpose();
        if (w.count == 3) {
            // The weights are coordinates of a point on the ray d.
            Eigen::Vector3d p = Eigen::Vector3d::Zero();
            for (std::size_t k = 0; k < 3; ++k) p += w.weight[k] * directions[w.index[k]];
            EXPECT_LT(angle_between(p.normalized(), d), 1e-12);
        }
        const auto nearest = interp.weights(d, Interpolation::Nearest);
        ASSERT_EQ(nearest.count, 1u);
        EXPECT_EQ(nearest.weight[0], 1.0);
        std::size_t best = 0;
        for (std::size_t i = 1; i < directions.size(); ++i)
            if (d.dot(directions[i]) > d.dot(directions[best])) best = i;
        EXPECT_EQ(nearest.index[0], best);
    }
    for (std::size_t i = 0; i < directions.size(); ++i) {
        const auto w = dense(interp.weights(directions[i]), directions.size());
        EXPECT_EQ(w[i], 1.0) << "direction " << i;
    }
}

TEST(Interpolation, ContinuousAcrossEdgesAndTheHorizonBoundary) {
    const auto directions = random_hemisphere(60, 13);
    const SphericalInterpolator interp(directions);
    const std::size_t n = directions.size();
    const double step = 1e-7;
    // Both sides of every edge of T, boundary edges included (the other side is the arc
    // interpolation), at five points along it.
    std::size_t checked = 0, boundary_checked = 0;
    for (const Triangle& t : interp.triangles())
        for (std::size_t e = 0; e < 3; ++e) {
            const Eigen::Vector3d& a = directions[t[e]];
            const Eigen::Vector3d& b = directions[t[(e + 1) % 3]];
            const Eigen::Vector3d normal = a.cross(b).normalized();
            for (const double s : {0.1, 0.3, 0.5, 0.7, 0.9}) {
                const Eigen::Vector3d p = ((1 - s) * a + s * b).normalized();
                const auto left = interp.weights((p + step * normal).normalized());
                const auto right = interp.weights((p - step * normal).normalized());
                EXPECT_LT(max_difference(dense(left, n), dense(right, n)), 1e-5)
                    << "edge " << t[e] << "-" << t[(e + 1) % 3] << " at " << s;
                ++checked;
                if (left.count == 2 || right.count == 2) ++boundary_checked;
            }
        }
    EXPECT_GT(checked, 0u);
    EXPECT_GT(boundary_checked, 10u);  // the horizon boundary was crossed
    // Across the azimuth of a boundary vertex below the horizon (eq. 4.7's interval ends).
    for (const std::size_t b : interp.boundary_vertices()) {
        const SphericalAngles angles = angles_of(directions[b]);
        const auto before = interp.weights(direction_from_angles(0.5 * kPi + 0.2, angles.phi - step));
        const auto after = interp.weights(direction_from_angles(0.5 * kPi + 0.2, angles.phi + step));
        EXPECT_LT(max_difference(dense(before, n), dense(after, n)), 1e-5);
    }
}

// Why the weights are not the solid-angle ratios of eq. 4.6: on an edge shared by two
// triangles, those ratios depend on the opposite vertex, so they jump across the edge.
TEST(Interpolation, SolidAngleRatiosOfEq46JumpAcrossAnEdge) {
    const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
    EXPECT_NEAR(spherical_triangle_solid_angle(x, y, z), 0.5 * kPi, 1e-15);  // an octant
    // A tiny triangle: its flat area; a hemisphere-sized one stays finite and accurate.
    const double h = 1e-5;
    EXPECT_NEAR(spherical_triangle_solid_angle(z, (z + h * x).normalized(), (z + h * y).normalized()),
                0.5 * h * h, 1e-20);
    // Three points on a great circle, not within a semicircle: a hemisphere.
    EXPECT_NEAR(spherical_triangle_solid_angle(x, y, (-x - y + 1e-9 * z).normalized()), 2.0 * kPi, 1e-6);

    const Eigen::Vector3d a = Eigen::Vector3d(1, 0, 0.2).normalized(), b = Eigen::Vector3d(0, 1, 0.2).normalized();
    const Eigen::Vector3d c1 = Eigen::Vector3d(0.3, 0.4, 1).normalized(), c2 = Eigen::Vector3d(1, 1, 0.1).normalized();
    const Eigen::Vector3d p = (0.75 * a + 0.25 * b).normalized();
    const double ratio1 = spherical_triangle_solid_angle(p, b, c1) / spherical_triangle_solid_angle(a, b, c1);
    const double ratio2 = spherical_triangle_solid_angle(p, b, c2) / spherical_triangle_solid_angle(a, b, c2);
    EXPECT_GT(std::abs(ratio1 - ratio2), 1e-3);
    // The interpolator's weights of the same point, for both triangles: identical.
    const SphericalInterpolator one({a, b, c1}), other({a, b, c2});
    EXPECT_NEAR(dense(one.weights(p), 3)[0], dense(other.weights(p), 3)[0], 1e-14);
}

// Eq. 4.6 as written: the same triangle as the Delaunay weights, sub-triangle solid angles
// (independent formula: l'Huilier through spherical_triangle_solid_angle's own tests) as
// weights, a partition of unity that reproduces each direction, and within a few percent
// of the continuous coordinates on triangles of about 10 degrees.
TEST(Interpolation, SolidAngleWeightsOfEq46) {
    const auto directions = random_hemisphere(300, 4);
    const SphericalInterpolator interp(directions);
    std::mt19937_64 random(8);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    double largest_difference = 0.0;
    for (int q = 0; q < 2000; ++q) {
        const double z = unit(random), phi = 2.0 * kPi * unit(random);
        const Eigen::Vector3d d(std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z);
        const auto planar = interp.weights(d);
        const auto solid = interp.weights(d, Interpolation::SolidAngle);
        expect_partition_of_unity(solid, directions.size());
        ASSERT_EQ(solid.count, planar.count);
        ASSERT_EQ(solid.index, planar.index);
        if (solid.count != 3) continue;
        const auto& a = directions[solid.index[0]];
        const auto& b = directions[solid.index[1]];
        const auto& c = directions[solid.index[2]];
        const double total = spherical_triangle_solid_angle(a, b, c);
        EXPECT_NEAR(solid.weight[0], spherical_triangle_solid_angle(d, b, c) / total, 1e-9);
        for (std::size_t k = 0; k < 3; ++k)
            largest_difference = std::max(largest_difference, std::abs(solid.weight[k] - planar.weight[k]));
    }
    EXPECT_GT(largest_difference, 0.0);
    EXPECT_LT(largest_difference, 0.05);
    for (std::size_t i = 0; i < directions.size(); ++i)
        EXPECT_EQ(dense(interp.weights(directions[i], Interpolation::SolidAngle), directions.size())[i], 1.0);
}

TEST(Interpolation, ThreeDirections) {
    const std::vector<Eigen::Vector3d> directions{direction_from_angles(0.3, 0.0), direction_from_angles(0.3, 2.0),
                                                  direction_from_angles(0.3, 4.0)};
    const SphericalInterpolator interp(directions);
    ASSERT_EQ(interp.triangles().size(), 1u);
    EXPECT_EQ(interp.boundary_vertices().size(), 3u);
    EXPECT_EQ(interp.weights(Eigen::Vector3d::UnitZ()).count, 3u);
    // Near the horizon: the arc interpolation between the two vertices bracketing phi.
    const auto w = interp.weights(direction_from_angles(1.5, 1.0));
    EXPECT_EQ(w.count, 2u);
    EXPECT_EQ(dense(w, 3)[2], 0.0);
    expect_partition_of_unity(w, 3);
    // Wrap-around (eq. 4.7): phi past the last boundary vertex (2 rad) and before the first
    // (4 rad = -2.28 rad) lies between vertices 1 and 2, on either side of phi = pi.
    for (const double phi : {3.0, -3.0}) {
        const auto wrapped = dense(interp.weights(direction_from_angles(1.5, phi)), 3);
        EXPECT_EQ(wrapped[0], 0.0);
        EXPECT_GT(wrapped[1], 0.0);
        EXPECT_GT(wrapped[2], 0.0);
    }
}

TEST(Interpolation, CocircularGridIsDeterministicAndComplete) {
    const auto directions = regular_grid(6, 16, degrees_to_radians(85.0));
    const SphericalInterpolator interp(directions);
    EXPECT_EQ(interp.triangles().size(), 2 * (directions.size() + 1) - 4 - interp.boundary_vertices().size());
    EXPECT_EQ(interp.boundary_vertices().size(), 16u);  // the lowest ring
    // Shuffled input: the same triangulation (CGAL breaks cospherical ties symbolically by
    // the points themselves, not by insertion order).
    std::vector<std::size_t> order(directions.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = (i * 37) % order.size();
    ASSERT_EQ(std::set<std::size_t>(order.begin(), order.end()).size(), order.size());
    std::vector<Eigen::Vector3d> shuffled;
    for (const std::size_t i : order) shuffled.push_back(directions[i]);
    std::vector<Triangle> mapped;
    const SphericalInterpolator shuffled_interp(shuffled);
    for (Triangle t : shuffled_interp.triangles()) {
        for (auto& v : t) v = order[v];
        mapped.push_back(t);
    }
    EXPECT_EQ(canonical_order(mapped), interp.triangles());
    // Every query above the lowest ring lies in a triangle; weights still a partition.
    std::mt19937_64 random(3);
    std::uniform_real_distribution<double> theta(0.0, degrees_to_radians(84.0)), phi(-kPi, kPi);
    for (int q = 0; q < 2000; ++q) {
        const auto w = interp.weights(direction_from_angles(theta(random), phi(random)));
        EXPECT_EQ(w.count, 3u);
        expect_partition_of_unity(w, directions.size());
    }
    // Queries exactly at the grid directions, which sit on many edges at once.
    for (std::size_t i = 0; i < directions.size(); ++i)
        EXPECT_NEAR(dense(interp.weights(directions[i]), directions.size())[i], 1.0, 1e-12);
}

TEST(Interpolation, DirectionsOnTheHorizon) {
    // A ring exactly on the horizon plus the zenith: T reaches the horizon, and just below
    // it the arc weights take over without a jump.
    std::vector<Eigen::Vector3d> directions{Eigen::Vector3d::UnitZ()};
    for (int c = 0; c < 8; ++c) directions.push_back(direction_from_angles(0.5 * kPi, 2.0 * kPi * c / 8));
    const SphericalInterpolator interp(directions);
    EXPECT_EQ(interp.triangles().size(), 8u);
    EXPECT_EQ(interp.boundary_vertices().size(), 8u);
    const double phi = 0.3;
    const auto above = dense(interp.weights(direction_from_angles(0.5 * kPi - 1e-9, phi)), 9);
    const auto below = dense(interp.weights(direction_from_angles(0.5 * kPi + 1e-9, phi)), 9);
    EXPECT_LT(max_difference(above, below), 1e-6);
    EXPECT_NEAR(above[0], 0.0, 1e-6);  // the zenith plays no part on the horizon
    // 3 degrees below the horizon is accepted, 10 degrees is not.
    directions.push_back(direction_from_angles(degrees_to_radians(93.0), 0.1));
    EXPECT_NO_THROW(SphericalInterpolator{directions});
    directions.back() = direction_from_angles(degrees_to_radians(100.0), 0.1);
    try {
        SphericalInterpolator{directions};
        FAIL() << "a direction 10 degrees below the horizon was accepted";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find("light direction 9"), std::string::npos) << error.what();
        EXPECT_NE(std::string(error.what()).find("below the horizon"), std::string::npos) << error.what();
    }
}

TEST(Interpolation, BadDirectionSetsAreInputErrors) {
    auto message_of = [](const std::vector<Eigen::Vector3d>& directions) {
        try {
            SphericalInterpolator{directions};
        } catch (const InputError& error) {
            return std::string(error.what());
        }
        return std::string("(accepted)");
    };
    auto directions = random_hemisphere(20, 4);
    directions.push_back(directions[7]);
    EXPECT_NE(message_of(directions).find("light directions 7 and 20 are the same direction"), std::string::npos)
        << message_of(directions);
    EXPECT_NE(message_of({Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX()}).find("at least 3"), std::string::npos);
    EXPECT_NE(message_of({Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::Zero()}).find("zero"),
              std::string::npos);
    // All on the great circle y = 0, which passes through the guardian: no triangle.
    EXPECT_NE(message_of({Eigen::Vector3d(std::sin(0.2), 0, std::cos(0.2)), Eigen::Vector3d(std::sin(0.9), 0, std::cos(0.9)),
                          Eigen::Vector3d(-std::sin(0.5), 0, std::cos(0.5))})
                  .find("one plane"),
              std::string::npos);
}

}  // namespace
}  // namespace rfd::relight
