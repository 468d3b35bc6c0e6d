// Lenslet lattices: the fast cell lookup against brute force, and the geometry.

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "optics/lattice.hpp"

namespace rfd::optics {
namespace {

CellIndex brute_force(const Lattice& lattice, const Eigen::Vector2d& p) {
    CellIndex best{};
    double best_d = std::numeric_limits<double>::infinity();
    for (int j = -3; j < lattice.count_y() + 3; ++j)
        for (int i = -3; i < lattice.count_x() + 3; ++i) {
            const double d = (lattice.center({i, j}) - p).squaredNorm();
            if (d < best_d) {
                best_d = d;
                best = {i, j};
            }
        }
    return best;
}

TEST(Lattice, CellAtIsTheNearestCentre) {
    std::mt19937_64 random(1);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (const Lattice& lattice : {Lattice::hexagonal(2.358, 7, 8), Lattice::hexagonal(1.0, 6, 5),
                                   Lattice::rectangular(4.0, 4.8, 6, 5), Lattice::rectangular(1.0, 2.0, 5, 4)}) {
        const Eigen::Vector2d half = lattice.half_extent();
        for (int k = 0; k < 100000; ++k) {
            const Eigen::Vector2d p(1.2 * half.x() * unit(random), 1.2 * half.y() * unit(random));
            const CellIndex fast = lattice.cell_at(p);
            const CellIndex slow = brute_force(lattice, p);
            // Away from shared edges the answers are identical; on an edge both are nearest.
            if (!(fast == slow)) {
                ASSERT_NEAR((lattice.center(fast) - p).norm(), (lattice.center(slow) - p).norm(), 1e-12);
            }
            ASSERT_TRUE(lattice.cell_contains(fast, p));
        }
    }
}

TEST(Lattice, CentresAverageToZero) {
    for (const Lattice& lattice : {Lattice::hexagonal(2.358, 7, 8), Lattice::hexagonal(2.358, 63, 73),
                                   Lattice::rectangular(4.0, 4.8, 6, 5)}) {
        Eigen::Vector2d sum = Eigen::Vector2d::Zero();
        for (int j = 0; j < lattice.count_y(); ++j)
            for (int i = 0; i < lattice.count_x(); ++i) sum += lattice.center({i, j});
        EXPECT_NEAR(sum.norm() / (lattice.count_x() * lattice.count_y()), 0.0, 1e-12);
    }
}

TEST(Lattice, HexagonalGeometry) {
    const Lattice hex = Lattice::hexagonal(2.358, 10, 10);
    EXPECT_NEAR(hex.density_per_mm2(), 2.0 / (std::sqrt(3.0) * 2.358 * 2.358), 1e-12);
    // The thesis's array: 20.77 lenses per square centimetre.
    const double pitch = std::sqrt(2.0 / (std::sqrt(3.0) * 0.2077));
    EXPECT_NEAR(pitch, 2.3578, 1e-4);
    EXPECT_NEAR(hex.boundary_distance({1, 0}), 2.358 / 2, 1e-12);
    EXPECT_NEAR(hex.boundary_distance({0, 1}), 2.358 / std::sqrt(3.0), 1e-12);
    EXPECT_NEAR(hex.circumradius(), 2.358 / std::sqrt(3.0), 1e-12);
    // Neighbours are one pitch apart, in six directions.
    const CellIndex c{4, 4};
    int neighbours = 0;
    for (int j = 3; j <= 5; ++j)
        for (int i = 3; i <= 5; ++i)
            if (!(CellIndex{i, j} == c) &&
                std::abs((hex.center({i, j}) - hex.center(c)).norm() - 2.358) < 1e-12)
                ++neighbours;
    EXPECT_EQ(neighbours, 6);
    // Corners of the cell lie on its boundary.
    for (const auto& corner : hex.cell_corners())
        EXPECT_NEAR(hex.boundary_distance(corner), corner.norm(), 1e-12);
}

TEST(Lattice, RectangularGeometryAndContainment) {
    const Lattice rect = Lattice::rectangular(4.0, 4.8, 6, 5);
    EXPECT_NEAR(rect.half_extent().x(), 12.0, 1e-12);
    EXPECT_NEAR(rect.half_extent().y(), 12.0, 1e-12);
    EXPECT_TRUE(rect.contains({5, 4}));
    EXPECT_FALSE(rect.contains({6, 0}));
    EXPECT_FALSE(rect.contains({0, -1}));
    EXPECT_NEAR(rect.boundary_distance(Eigen::Vector2d(4.0, 4.8)), std::hypot(2.0, 2.4), 1e-12);
    const CellIndex outside = rect.cell_at({12.5, 0.0});
    EXPECT_FALSE(rect.contains(outside));
}

}  // namespace
}  // namespace rfd::optics
