// Repulsion patterns against the geometry of an ideal hexagonal lattice on the hemisphere.

#include <algorithm>
#include <cmath>
#include <numeric>

#include <gtest/gtest.h>

#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/sampling.hpp"

namespace rfd::relight {
namespace {

// The largest angle from any point of the hemisphere (z >= 0) to its nearest pattern
// direction, estimated on a dense Fibonacci probe set.
double covering_radius(const std::vector<Eigen::Vector3d>& pattern) {
    double worst = 0.0;
    for (const Eigen::Vector3d& probe : fibonacci_hemisphere(20000)) {
        double nearest = kPi;
        for (const auto& d : pattern) nearest = std::min(nearest, angle_between(probe, d));
        worst = std::max(worst, nearest);
    }
    return worst;
}

TEST(Repulsion, PointsAreUnitOnTheUpperHemisphereAndExactlyCounted) {
    for (std::size_t count : {1u, 2u, 3u, 7u, 64u, 300u}) {
        const auto pattern = repulsion_pattern(count, 5);
        ASSERT_EQ(pattern.size(), count);
        for (const auto& d : pattern) {
            EXPECT_NEAR(d.norm(), 1.0, 1e-12);
            EXPECT_GT(d.z(), 0.0);
        }
    }
    EXPECT_TRUE(repulsion_pattern(0, 5).empty());
}

// An ideal hexagonal lattice of side a has nearest neighbours at a and covers the surface
// within a / sqrt(3). Relaxed repulsion gets close: nearest neighbours within 20% of a
// everywhere (the horizon rows and the lattice defects that a sphere forces are the worst)
// and a covering radius within 35% of the ideal.
TEST(Repulsion, SpacingIsNearlyHexagonal) {
    for (std::size_t count : {64u, 256u}) {
        const auto pattern = repulsion_pattern(count, 11);
        const double a = ideal_spacing(count);
        const auto nearest = nearest_neighbour_angles(pattern);
        const double smallest = *std::min_element(nearest.begin(), nearest.end());
        const double mean = std::accumulate(nearest.begin(), nearest.end(), 0.0) /
                            static_cast<double>(nearest.size());
        EXPECT_GT(smallest, 0.8 * a) << count;
        EXPECT_NEAR(mean, a, 0.1 * a) << count;
        EXPECT_LT(covering_radius(pattern), 1.35 * a / std::sqrt(3.0)) << count;
    }
}

// The horizon band is covered: no probe at the horizon is farther from the pattern than a
// spacing, and no direction sits lower than a small fraction of one.
TEST(Repulsion, CoversTheHorizonBandWithoutCollectingOnIt) {
    const auto pattern = repulsion_pattern(256, 3);
    const double a = ideal_spacing(256);
    double lowest = 1.0;
    for (const auto& d : pattern) lowest = std::min(lowest, std::asin(d.z()));
    EXPECT_GT(lowest, 0.2 * a);
    EXPECT_LT(lowest, a);
    for (int k = 0; k < 360; ++k) {
        const Eigen::Vector3d horizon = direction_from_angles(kPi / 2, kPi * k / 180.0);
        double nearest = kPi;
        for (const auto& d : pattern) nearest = std::min(nearest, angle_between(horizon, d));
        EXPECT_LT(nearest, a) << "azimuth " << k;
    }
}

TEST(Repulsion, RelaxationLowersTheEnergyOfTheStart) {
    RepulsionOptions start_only;
    start_only.max_iterations = 0;
    const double start = repulsion_energy(repulsion_pattern(200, 9, start_only));
    RepulsionOptions few;
    few.max_iterations = 5;
    const double early = repulsion_energy(repulsion_pattern(200, 9, few));
    const double relaxed = repulsion_energy(repulsion_pattern(200, 9));
    EXPECT_LT(early, start);
    EXPECT_LT(relaxed, early);
}

// Energy of an independent computation: all pairs of the 2n charges (pattern and mirror
// images), halved.
TEST(Repulsion, EnergyMatchesAllPairsOfChargesAndImages) {
    const auto pattern = repulsion_pattern(20, 2);
    std::vector<Eigen::Vector3d> charges = pattern;
    for (const auto& d : pattern) charges.emplace_back(d.x(), d.y(), -d.z());
    double total = 0.0;
    for (std::size_t i = 0; i < charges.size(); ++i)
        for (std::size_t j = i + 1; j < charges.size(); ++j) total += 1.0 / (charges[i] - charges[j]).norm();
    EXPECT_NEAR(repulsion_energy(pattern), 0.5 * total, 1e-9 * total);
}

TEST(Repulsion, SameSeedSamePatternOtherSeedOtherPattern) {
    const auto a = repulsion_pattern(100, 42);
    const auto b = repulsion_pattern(100, 42);
    const auto c = repulsion_pattern(100, 43);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]);
    double moved = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) moved = std::max(moved, (a[i] - c[i]).norm());
    EXPECT_GT(moved, 0.01);
}

// Few charges settle where symmetry puts them: one at the pole; two opposite in azimuth at
// equal heights; three at 120 degrees.
TEST(Repulsion, FewChargesFindTheSymmetricEquilibria) {
    const auto one = repulsion_pattern(1, 1);
    EXPECT_NEAR(one[0].z(), 1.0, 1e-3);
    const auto two = repulsion_pattern(2, 1);
    EXPECT_NEAR(two[0].z(), two[1].z(), 1e-3);
    EXPECT_NEAR(angles_of(two[0]).phi - angles_of(two[1]).phi, (angles_of(two[0]).phi > angles_of(two[1]).phi ? kPi : -kPi), 1e-2);
    const auto three = repulsion_pattern(3, 1);
    for (std::size_t i = 0; i < 3; ++i) {
        EXPECT_NEAR(three[i].z(), three[(i + 1) % 3].z(), 1e-3);
        const Eigen::Vector2d a = three[i].head<2>().normalized();
        const Eigen::Vector2d b = three[(i + 1) % 3].head<2>().normalized();
        EXPECT_NEAR(a.dot(b), -0.5, 1e-2);
    }
}

}  // namespace
}  // namespace rfd::relight
