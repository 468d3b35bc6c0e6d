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

TEST(Lattice, CellExitIsWhereAHorizontalLineLeavesTheCell) {
    std::mt19937_64 random(7);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (const Lattice& lattice : {Lattice::hexagonal(2.358, 7, 8), Lattice::rectangular(4.0, 4.8, 6, 5)}) {
        const Eigen::Vector2d half = lattice.half_extent();
        const double eps = 1e-9 * lattice.pitch_x();
        for (int k = 0; k < 20000; ++k) {
            const Eigen::Vector2d p(half.x() * unit(random), half.y() * unit(random));
            const CellIndex cell = lattice.cell_at(p);
            const double exit = lattice.kind() == LatticeKind::Hexagonal
                                    ? lattice.cell_exit_x_of<LatticeKind::Hexagonal>(cell, p.y())
                                    : lattice.cell_exit_x_of<LatticeKind::Rectangular>(cell, p.y());
            ASSERT_GE(exit, p.x() - eps);
            ASSERT_TRUE(lattice.cell_contains(cell, {exit - eps, p.y()})) << k;
            ASSERT_FALSE(lattice.cell_contains(cell, {exit + eps, p.y()})) << k;
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
    // The thesis's array, 20.77 lenses per square centimetre, has a 2.3578 mm pitch.
    EXPECT_NEAR(Lattice::hexagonal(2.3578, 10, 10).density_per_mm2() * 100.0, 20.77, 0.005);
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

namespace rfd::optics {
namespace {

// The outer boundary of the array, from the corners of every cell.
Eigen::Vector2d true_half_extent(const Lattice& lattice) {
    Eigen::Vector2d half = Eigen::Vector2d::Zero();
    for (int j = 0; j < lattice.count_y(); ++j)
        for (int i = 0; i < lattice.count_x(); ++i)
            for (const auto& corner : lattice.cell_corners())
                half = half.cwiseMax((lattice.center({i, j}) + corner).cwiseAbs());
    return half;
}

TEST(Lattice, HalfExtentIsTheOuterBoundaryOfTheCells) {
    // Odd and even row counts: with an odd number of rows (> 1) a hexagonal array is not
    // symmetric about x = 0 (more rows unshifted than shifted), and the wider side counts.
    for (const Lattice& lattice :
         {Lattice::hexagonal(1.0, 4, 1), Lattice::hexagonal(1.0, 4, 2), Lattice::hexagonal(1.0, 4, 3),
          Lattice::hexagonal(2.358, 9, 9), Lattice::hexagonal(2.358, 10, 7), Lattice::hexagonal(0.7, 5, 12),
          Lattice::rectangular(4.0, 4.8, 6, 5), Lattice::rectangular(1.0, 2.0, 3, 8)}) {
        const Eigen::Vector2d expected = true_half_extent(lattice);
        EXPECT_NEAR(lattice.half_extent().x(), expected.x(), 1e-12)
            << lattice.count_x() << "x" << lattice.count_y();
        EXPECT_NEAR(lattice.half_extent().y(), expected.y(), 1e-12)
            << lattice.count_x() << "x" << lattice.count_y();
    }
    // Closed form for 4 x 3 hexagonal cells of pitch 1: rows 0 and 2 unshifted, row 1
    // shifted by 1/2, all moved left by the mean shift (1/2)(1/3) = 1/6; the right side
    // reaches 1.5 + 1/2 + 1/2 - 1/6 = 7/3, the left one 1.5 + 1/6 + 1/2 = 13/6.
    EXPECT_NEAR(Lattice::hexagonal(1.0, 4, 3).half_extent().x(), 7.0 / 3.0, 1e-12);
}

TEST(Lattice, PointsOnSharedEdgesFollowTheDocumentedRule) {
    // Exactly representable ties (pitch 1, centres on multiples of 1/2 or 1/4).
    const Lattice rect = Lattice::rectangular(1.0, 1.0, 4, 4);  // centres at -1.5 ... 1.5
    EXPECT_EQ(rect.cell_at({-1.0, 0.25}), (CellIndex{1, 2}));      // column edge: higher column
    EXPECT_EQ(rect.cell_at({0.25, -1.0}), (CellIndex{2, 1}));      // row edge: higher row
    const Lattice hex = Lattice::hexagonal(1.0, 4, 2);             // row 0 centres at -1.75 ...
    const Eigen::Vector2d a = hex.center({1, 0}), b = hex.center({2, 0});
    EXPECT_EQ(0.5 * (a + b), Eigen::Vector2d(-0.25, a.y()));      // the tie is exact
    EXPECT_EQ(hex.cell_at(0.5 * (a + b)), (CellIndex{2, 0}));     // within a row: higher column
    // Whatever the tie, the cell returned contains the point.
    EXPECT_TRUE(hex.cell_contains(hex.cell_at(0.5 * (a + b)), 0.5 * (a + b)));
    EXPECT_TRUE(rect.cell_contains(rect.cell_at({-1.0, -1.0}), {-1.0, -1.0}));
}

TEST(Lattice, FarPointsGiveFarCellsWithoutOverflow) {
    // A paraxial ray at a slope of 1e12 lands a kilometre-scale distance away: its cell is
    // far outside the array on the correct side (an int overflow would flip the sign).
    for (const Lattice& lattice : {Lattice::hexagonal(2.358, 9, 9), Lattice::rectangular(1.0, 1.0, 4, 4)}) {
        for (double far : {1e8, 1e12, 1e300, HUGE_VAL}) {
            const CellIndex right = lattice.cell_at({far, 0.0});
            const CellIndex up = lattice.cell_at({0.0, far});
            const CellIndex left = lattice.cell_at({-far, -far});
            EXPECT_GT(right.i, lattice.count_x()) << far;
            EXPECT_GT(up.j, lattice.count_y()) << far;
            EXPECT_LT(left.i, 0) << far;
            EXPECT_LT(left.j, 0) << far;
            EXPECT_FALSE(lattice.contains(right));
        }
        EXPECT_FALSE(lattice.contains(lattice.cell_at({std::nan(""), 0.0})));
    }
}

TEST(Lattice, BoundaryDistanceMatchesContainmentAlongRandomDirections) {
    // boundary_distance(dir) is the largest s with centre + s dir still in the cell.
    std::mt19937_64 random(21);
    std::uniform_real_distribution<double> angle(-3.14159265358979, 3.14159265358979);
    for (const Lattice& lattice : {Lattice::hexagonal(2.358, 5, 5), Lattice::rectangular(4.0, 4.8, 5, 5)}) {
        const CellIndex cell{2, 3};
        const Eigen::Vector2d centre = lattice.center(cell);
        for (int k = 0; k < 2000; ++k) {
            const double phi = angle(random);
            const Eigen::Vector2d dir(std::cos(phi), std::sin(phi));
            double inside = 0.0, outside = 2.0 * lattice.circumradius();
            for (int step = 0; step < 80; ++step) {
                const double mid = 0.5 * (inside + outside);
                (lattice.cell_contains(cell, centre + mid * dir) ? inside : outside) = mid;
            }
            EXPECT_NEAR(lattice.boundary_distance(dir), inside, 1e-9) << phi;
            EXPECT_LE(lattice.boundary_distance(dir), lattice.circumradius() + 1e-12);
            EXPECT_GE(lattice.boundary_distance(dir), 0.5 * std::min(lattice.pitch_x(), lattice.pitch_y()) - 1e-12);
        }
    }
}

TEST(Lattice, HexagonCornersAreWhereThreeCellsMeet) {
    // Each corner of a hexagonal cell is equidistant (at the circumradius) from its own
    // centre and two neighbouring centres, and no centre is nearer.
    const Lattice hex = Lattice::hexagonal(2.358, 8, 8);
    for (const CellIndex cell : {CellIndex{3, 3}, CellIndex{4, 4}, CellIndex{0, 0}, CellIndex{7, 6}}) {
        for (const auto& corner : hex.cell_corners()) {
            const Eigen::Vector2d p = hex.center(cell) + corner;
            int at_circumradius = 0;
            for (int j = cell.j - 2; j <= cell.j + 2; ++j)
                for (int i = cell.i - 2; i <= cell.i + 2; ++i) {
                    const double d = (hex.center({i, j}) - p).norm();
                    EXPECT_GE(d, hex.circumradius() - 1e-12);
                    if (std::abs(d - hex.circumradius()) < 1e-12) ++at_circumradius;
                }
            EXPECT_EQ(at_circumradius, 3);
        }
    }
}

TEST(Lattice, ThesisDensityRoundTripsThroughThePitch) {
    // 20.77 lenses per cm^2 in a hexagonal array: pitch = sqrt(2 / (sqrt(3) rho)) = 2.35785 mm;
    // the lattice built with it reports that density back.
    const double rho_per_mm2 = 20.77 / 100.0;
    const double pitch = std::sqrt(2.0 / (std::sqrt(3.0) * rho_per_mm2));
    EXPECT_NEAR(pitch, 2.35785, 5e-6);
    const Lattice hex = Lattice::hexagonal(pitch, 40, 40);
    EXPECT_NEAR(hex.density_per_mm2() * 100.0, 20.77, 1e-12);
    EXPECT_NEAR(hex.cell_area(), std::sqrt(3.0) / 2.0 * pitch * pitch, 1e-12);
    // Counting centres in a large disc gives the same density (to the boundary's share).
    const Lattice big = Lattice::hexagonal(pitch, 201, 201);
    const double radius = 150.0;
    int inside = 0;
    for (int j = 0; j < big.count_y(); ++j)
        for (int i = 0; i < big.count_x(); ++i)
            if (big.center({i, j}).norm() < radius) ++inside;
    EXPECT_NEAR(inside / (3.14159265358979 * radius * radius), rho_per_mm2, 0.003 * rho_per_mm2);
}

}  // namespace
}  // namespace rfd::optics
