// Analyses of a design checked against closed forms and against each other: the paraxial
// wrap-over angle, the exact wrap-over found by bisection, the inverse map as a round
// trip, and the design rules that must fire.

#include <cmath>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/units.hpp"
#include "optics/accuracy_chart.hpp"
#include "optics/analysis.hpp"

#include "tests/support/bundled.hpp"

namespace rfd::optics {
namespace {

using ::testing::HasSubstr;
using rfd::testing::bundled_design;

TEST(Analysis, ParaxialWrapOverIsTheClosedForm) {
    // The chief ray through a lenslet's vertex lands at B tan(theta) (B of the lenslet's
    // matrix); it leaves a hexagonal cell at pitch/2 along the flat direction and at
    // pitch/sqrt(3) toward the corner.
    const DesignOptics optics(bundled_design(1));
    const double b = std::abs(optics.paraxial_b());
    const double pitch = optics.lattice().pitch_x();
    const double flat = radians_to_degrees(std::atan(0.5 * pitch / b));
    const double corner = radians_to_degrees(std::atan(pitch / std::sqrt(3.0) / b));
    EXPECT_NEAR(*wrap_over_angle(optics, 0.0, Model::Paraxial), flat, 1e-6);
    EXPECT_NEAR(*wrap_over_angle(optics, kPi / 2, Model::Paraxial), corner, 1e-6);
    // For a plano-convex lenslet with the pattern at focus, B is the focal length.
    EXPECT_NEAR(b, 3.0, 1e-3);
}

TEST(Analysis, ExactWrapOverIsWhereTheChiefRayLeavesTheCell) {
    for (int n : {1, 2}) {
        const DesignOptics optics(bundled_design(n));
        const CellIndex cell = optics.centre_cell();
        const double angle = *wrap_over_angle(optics, 0.0, Model::Exact);
        const auto before = optics.land(incident_direction(degrees_to_radians(angle - 1e-6), 0.0), cell, Model::Exact);
        const auto after = optics.land(incident_direction(degrees_to_radians(angle + 1e-6), 0.0), cell, Model::Exact);
        EXPECT_EQ(before.status, RayStatus::Ok) << n;
        EXPECT_EQ(after.status, RayStatus::CrossedCell) << n;
        if (n == 1) {
            // Design I crosses on the pattern plane, at the cell's flat edge.
            EXPECT_NEAR(std::abs(before.offset.x()), 0.5 * optics.lattice().pitch_x(), 1e-6);
        }
    }
}

TEST(Analysis, ModelsAgreeNearTheAxisAndDivergeAtSteepAngles) {
    const DesignOptics optics(bundled_design(1));
    const CellIndex cell = optics.centre_cell();
    const auto small = incident_direction(1e-5, 0.3);
    const auto p = optics.land(small, cell, Model::Paraxial);
    const auto e = optics.land(small, cell, Model::Exact);
    EXPECT_NEAR((p.offset - e.offset).norm() / p.offset.norm(), 0.0, 1e-6);
    const auto steep = incident_direction(degrees_to_radians(20.0), 0.0);
    const double error = (optics.land(steep, cell, Model::Paraxial).offset -
                          optics.land(steep, cell, Model::Exact).offset).norm();
    EXPECT_GT(error, optics.dot_mm().x());  // more than a print pixel at 20 degrees
}

TEST(Analysis, InverseMapRoundTripsThroughTheForwardMap) {
    for (int n : {1, 2}) {
        const DesignOptics optics(bundled_design(n));
        const CellIndex cell = optics.centre_cell();
        const Lattice& lattice = optics.lattice();
        std::mt19937_64 random(7);
        std::uniform_real_distribution<double> unit(-1.0, 1.0);
        int checked = 0;
        for (int k = 0; k < 200; ++k) {
            const Eigen::Vector2d offset(0.6 * 0.5 * lattice.pitch_x() * unit(random),
                                         0.6 * 0.5 * lattice.pitch_y() * unit(random));
            for (Model model : {Model::Paraxial, Model::Exact}) {
                const auto direction = optics.direction_for(offset, cell, model);
                ASSERT_TRUE(direction.has_value()) << n << " " << to_string(model);
                EXPECT_NEAR(direction->norm(), 1.0, 1e-12);
                const auto landed = optics.land(*direction, cell, model);
                ASSERT_EQ(landed.status, RayStatus::Ok);
                EXPECT_NEAR((landed.offset - offset).norm(), 0.0, 1e-8)
                    << "design " << n << " " << to_string(model);
                ++checked;
            }
        }
        EXPECT_EQ(checked, 400);
    }
}

TEST(Analysis, InverseMapRefusesPositionsBeyondWrapOver) {
    // A position outside the lenslet's cell has no incident direction under that lenslet.
    const DesignOptics optics(bundled_design(1));
    const Eigen::Vector2d outside(0.6 * optics.lattice().pitch_x(), 0.0);
    EXPECT_FALSE(optics.direction_for(outside, optics.centre_cell(), Model::Exact).has_value());
}

TEST(Analysis, BundleOnAxisArrivesWholeAndSpotShrinksWithAperture) {
    const DesignOptics optics(bundled_design(1));
    const auto bundle = optics.trace_bundle(incident_direction(0, 0), optics.centre_cell(), 31);
    EXPECT_GT(bundle.rays, 500u);
    EXPECT_EQ(bundle.arrived, bundle.rays);
    EXPECT_EQ(bundle.crossed, 0u);
    // A spherical f/1.3 lenslet: the RMS spot at the paraxial focus is dominated by
    // spherical aberration, far above a print dot but well inside the cell.
    EXPECT_GT(bundle.rms_spot_radius, optics.dot_mm().x());
    EXPECT_LT(bundle.rms_spot_radius, 0.5 * optics.lattice().pitch_x());
}

TEST(Analysis, FlatSideFirstLensletsWarnAboutTotalInternalReflection) {
    // Turning Design I's array round sends rays at the rim onto the curved exit beyond the
    // critical angle (sin(theta) = r/R > 1/n for r > R/n = 0.99 mm).
    Design design = bundled_design(1);
    for (auto& plane : design.planes)
        if (plane.name == "A") plane.curved_side = CurvedSide::Observer;
    const DesignOptics optics(design);
    const auto summary = summarise(optics);
    bool warned = false;
    for (const auto& warning : summary.warnings)
        warned = warned || warning.find("total internal reflection") != std::string::npos;
    EXPECT_TRUE(warned);
    EXPECT_LT(summary.efficiency_on_axis, 0.9);
}

TEST(Analysis, SummaryCountsDirectionsPerLenslet) {
    const DesignOptics optics(bundled_design(1));
    const auto summary = summarise(optics);
    // Hex cell area pitch^2 sqrt(3)/2 over one 2880 x 1440 dpi dot.
    const double pitch = optics.lattice().pitch_x();
    const double dots = pitch * pitch * std::sqrt(3.0) / 2 / ((25.4 / 2880) * (25.4 / 1440));
    EXPECT_NEAR(summary.directions_per_lenslet, dots, 1e-6);
    EXPECT_NEAR(summary.efficiency_on_axis, 1.0, 1e-12);
    EXPECT_TRUE(summary.warnings.empty()) << summary.warnings.front();
}

TEST(Analysis, DesignTwoWarnsThatThickLensletsMagnifyTheMacroPixels) {
    const auto summary = summarise(DesignOptics(bundled_design(2)));
    ASSERT_GE(summary.conjugates.size(), 2u);
    EXPECT_GT(std::abs(summary.conjugates[1].magnification), 1.1);
    bool warned = false;
    for (const auto& w : summary.warnings) warned = warned || w.find("overlap") != std::string::npos;
    EXPECT_TRUE(warned);
}

// The crosstalk onset by brute force: a dense grid of 41 x 41 points spanning the centre
// lenslet's cell edge to edge (corners and rim included, a hair inside so that every ray
// enters this lenslet), each the point where a ray of the parallel beam meets the lenslet's
// surface (at the sag below its vertex plane); each ray traced alone at rising angles along
// phi in kDenseStep steps, the step where it first ends under a neighbour refined by
// bisection. The onset is the smallest such angle.
constexpr double kDenseStep = 0.05;  // deg

double dense_crosstalk_onset(const DesignOptics& optics, double phi) {
    const Lattice& lattice = optics.lattice();
    const SequentialSystem& system = optics.system();
    const Surface& entry = system.surfaces.front();
    const CellIndex cell = optics.centre_cell();
    const Eigen::Vector2d centre = lattice.center(cell);
    // Half-widths of the cell: a hexagon's flats at +-pitch/2 and corners at +-pitch/sqrt(3).
    const Eigen::Vector2d half = lattice.kind() == LatticeKind::Hexagonal
                                     ? Eigen::Vector2d(0.5 * lattice.pitch_x(), lattice.pitch_x() / std::sqrt(3.0))
                                     : Eigen::Vector2d(0.5 * lattice.pitch_x(), 0.5 * lattice.pitch_y());
    auto crosses = [&](const Eigen::Vector2d& offset, double degrees) {
        const Eigen::Vector3d d = incident_direction(degrees_to_radians(degrees), phi);
        const double r2 = offset.squaredNorm();
        const double z = entry.z + curvature_of(entry.profile) * r2 /
                                       (1.0 + std::sqrt(1.0 - curvature_of(entry.profile) *
                                                                  curvature_of(entry.profile) * r2));
        const Eigen::Vector3d on_lens(centre.x() + offset.x(), centre.y() + offset.y(), z);
        const Ray ray{on_lens - (5.0 / d.z()) * d, d};
        return trace(system, ray).status == RayStatus::CrossedCell;
    };
    double onset = 90.0;
    constexpr int kSide = 41;  // (kSide - 1) / 4 whole: the grid holds the hexagon's six corners
    for (int iy = 0; iy < kSide; ++iy) {
        for (int ix = 0; ix < kSide; ++ix) {
            const Eigen::Vector2d unit(2.0 * ix / (kSide - 1) - 1.0, 2.0 * iy / (kSide - 1) - 1.0);
            const Eigen::Vector2d offset = (1.0 - 1e-9) * half.cwiseProduct(unit);
            if (!lattice.cell_contains(cell, centre + offset)) continue;
            for (double hi = kDenseStep; hi < onset; hi += kDenseStep) {
                if (!crosses(offset, hi)) continue;
                double lo = hi - kDenseStep;
                for (int i = 0; i < 30; ++i) {
                    const double mid = 0.5 * (lo + hi);
                    (crosses(offset, mid) ? hi : lo) = mid;
                }
                onset = std::min(onset, hi);
                break;
            }
        }
    }
    return onset;
}

// Crosstalk begins where the first light of the beam entering a lenslet lands under a
// neighbour. The design summary's onset must agree with the dense bundle to within its
// angle step (it was 0.9 deg late for Design II and 6 deg for Design I, whose first light
// to cross enters the steep corners of the lenslets).
TEST(Analysis, CrosstalkOnsetAgreesWithADenseBundle) {
    for (int n : {1, 2}) {
        const DesignOptics optics(bundled_design(n));
        const DesignSummary summary = summarise(optics);
        const Lattice& lattice = optics.lattice();
        std::vector<double> phis = {0.0, kPi / 2};
        if (lattice.kind() == LatticeKind::Rectangular) phis.push_back(std::atan2(lattice.pitch_y(), lattice.pitch_x()));
        ASSERT_EQ(summary.crosstalk_exact_deg.size(), phis.size());
        for (std::size_t k = 0; k < phis.size(); ++k) {
            const double dense = dense_crosstalk_onset(optics, phis[k]);
            ASSERT_TRUE(summary.crosstalk_exact_deg[k].second);
            EXPECT_NEAR(*summary.crosstalk_exact_deg[k].second, dense, kDenseStep)
                << "Design " << n << " along " << summary.crosstalk_exact_deg[k].first;
        }
    }
}

TEST(Analysis, ChartMarksWhereParaxialErrorPassesHalfAPixel) {
    const DesignOptics optics(bundled_design(1));
    const Chart chart = accuracy_chart(optics, 0.0, "x", 20.0, 80);
    ASSERT_EQ(chart.rows.size(), 81u);
    EXPECT_NEAR(chart.rows.front().error_um, 0.0, 1e-9);
    ASSERT_TRUE(chart.half_pixel_angle_deg.has_value());
    // Before the mark every error is under half a pixel, at the mark it is over.
    for (const auto& row : chart.rows) {
        if (row.angle_deg < *chart.half_pixel_angle_deg) {
            EXPECT_LE(std::abs(row.error_pixels), 0.5);
        }
        if (row.angle_deg == *chart.half_pixel_angle_deg) {
            EXPECT_GT(std::abs(row.error_pixels), 0.5);
        }
    }
}

}  // namespace
}  // namespace rfd::optics
