// The optics behind a dot of Designs III/IV (optics/meso_pixel.hpp) against closed forms:
// the front-focal-plane rule tan = -p/f, the matrix product for the output gain, aperture
// tests done with matrices instead of the surface-by-surface tracer, round trips of the
// inverse maps, and where the two models part.

#include <cmath>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "optics/meso_pixel.hpp"

#include "tests/support/bundled.hpp"

namespace rfd::optics {
namespace {

using ::testing::HasSubstr;
using rfd::testing::bundled_design;

// Design III with an almost flat pattern pair (R = 1e5 mm) and projection lenslets of
// f = R / (n - 1) = 10 mm placed so that the pattern lies in their front focal plane:
// reduced distance 2/1.5 (pattern to the pair's back) + gap + 2/1.5 (E's glass) = 10 mm.
constexpr double kProjectionFocal = 10.0;
std::string focused_design() {
    const double gap = kProjectionFocal - 2.0 * 2.0 / 1.5;
    const double z_d = 65.1466, z_e = z_d + 2.0 + gap;
    return R"(
[design]
name = "focused III"
kind = "III"
[printer]
dpi_x = 2880
dpi_y = 1440
[parts.main]
type = "lens"
radius_mm = 25.84
center_thickness_mm = 5.3
material = "N-BK7"
diameter_mm = 25.0
focal_length_mm = 50.0
[parts.field]
type = "lens"
radius_mm = 25.84
center_thickness_mm = 6.5
material = "N-BK7"
diameter_mm = 30.0
focal_length_mm = 50.0
[parts.meso]
type = "lenslet_array"
lattice = "rectangular"
pitch_mm = [4.0, 4.8]
count = [6, 5]
radius_mm = 5.4915
center_thickness_mm = 2.0
material = "B270"
focal_length_mm = 10.5
[parts.flat]
type = "lenslet_array"
lattice = "rectangular"
pitch_mm = [4.0, 4.8]
count = [6, 5]
radius_mm = 100000.0
center_thickness_mm = 2.0
index = 1.5
focal_length_mm = 200000.0
[parts.projection]
type = "lenslet_array"
lattice = "rectangular"
pitch_mm = [4.0, 4.8]
count = [6, 5]
radius_mm = 5.0
center_thickness_mm = 2.0
index = 1.5
focal_length_mm = 10.0
[planes.A]
z_mm = 0.0
part = "main"
curved_side = "light"
[planes.B]
z_mm = 47.0154
part = "field"
curved_side = "observer"
[planes.C]
z_mm = 54.0154
part = "meso"
curved_side = "light"
[planes.D]
z_mm = )" + std::to_string(z_d) + R"(
part = "flat"
arrangement = "back_to_back"
pattern = true
[planes.E]
z_mm = )" + std::to_string(z_e) + R"(
part = "projection"
curved_side = "observer"
)";
}

Eigen::Vector2d slopes(const Eigen::Vector3d& d) { return {d.x() / d.z(), d.y() / d.z()}; }

TEST(MesoPixel, APatternPointInTheFrontFocalPlaneLeavesAtMinusPOverF) {
    const DesignOptics optics(parse_design(focused_design(), "focused.toml"));
    const MesoPixelOptics meso(optics);
    // The pair's back surface keeps a power of 0.5/1e5 per mm: 5e-5 of the lenslets'.
    EXPECT_NEAR(meso.output_gain(), -1.0 / kProjectionFocal, 1e-4 / kProjectionFocal);
    // In focus, every ray of a dot leaves parallel: no spread.
    EXPECT_LT(meso.output_spread().norm(), 1e-5);
    const CellIndex cell{2, 2};
    for (const Eigen::Vector2d& p : {Eigen::Vector2d(0.3, 0.0), Eigen::Vector2d(-0.5, 0.8)}) {
        const DotRay ray = meso.dot(p, cell, Model::Paraxial);
        ASSERT_EQ(ray.light, DotLight::Lit);
        EXPECT_NEAR((slopes(ray.output) + p / kProjectionFocal).norm(), 0.0, 1e-4 * p.norm());
    }
    // Exact: the same near the axis (spherical aberration grows as p^3).
    const Eigen::Vector2d small(0.02, -0.01);
    const DotRay exact = meso.dot(small, cell, Model::Exact);
    ASSERT_EQ(exact.light, DotLight::Lit);
    EXPECT_NEAR((slopes(exact.output) + small / kProjectionFocal).norm(), 0.0, 1e-3 * small.norm());
}

TEST(MesoPixel, ParaxialTraceEqualsTheMatrixGainInEveryCell) {
    const DesignOptics optics(bundled_design(3));
    const MesoPixelOptics meso(optics);
    const SequentialSystem& system = optics.system();
    // gain = C_de + D_de D_cd / B_cd, from two matrix products; the dot's output comes from
    // the surface-by-surface tracer.
    const RayMatrix cd = vertex_matrix(system, meso.meso_front(), meso.pattern_surface());
    const RayMatrix de = vertex_matrix(system, meso.pattern_surface(), meso.last_surface());
    EXPECT_DOUBLE_EQ(meso.output_gain(), de.c + de.d * cd.d / cd.b);
    // The design's focal condition is for E alone; the pair's back surface adds power, so the
    // projection is shorter than E's 10.5 mm and the beam is not quite parallel.
    EXPECT_GT(-1.0 / meso.output_gain(), 8.0);
    EXPECT_LT(-1.0 / meso.output_gain(), 10.5);
    EXPECT_GT(meso.output_spread().x(), 1e-3);
    int lit = 0;
    for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 6; ++i)
            for (const Eigen::Vector2d& p : {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1.3, -0.7),
                                            Eigen::Vector2d(-1.5, 0.8)}) {
                const DotRay ray = meso.dot(p, {i, j}, Model::Paraxial);
                ASSERT_EQ(ray.light, DotLight::Lit) << i << " " << j;
                EXPECT_NEAR((slopes(ray.output) - meso.output_gain() * p).norm(), 0.0, 1e-12);
                // Every ray through C_k's vertex comes from the bin's centre direction (C
                // lies within 2e-5 mm of the focus of A and B: 1e-7 of slope).
                const Eigen::Vector3d centre = *optics.direction_for(optics.lattice().center({i, j}), {i, j}, Model::Paraxial);
                EXPECT_NEAR((ray.incident - centre).norm(), 0.0, 1e-7);
                ++lit;
            }
    EXPECT_EQ(lit, 90);
}

TEST(MesoPixel, DotsOutsideTheMainLensImageAreUnlitAsTheMatricesPredict) {
    // Independent of the tracer: carry the chief ray with vertex matrices from A to E and
    // test every aperture; the corners of the 4 x 4.8 mm cells lie outside the ~2.3 mm
    // image of the main lens.
    const DesignOptics optics(bundled_design(3));
    const MesoPixelOptics meso(optics);
    const SequentialSystem& system = optics.system();
    const std::size_t c = meso.meso_front();
    const RayMatrix cd = vertex_matrix(system, c, meso.pattern_surface());
    // From A's front (just in front) to C's vertex plane (just in front of C).
    const RayMatrix ac = translation(system.surfaces[c].z - system.surfaces[c - 1].z) * vertex_matrix(system, 0, c - 1);
    const Lattice& lattice = optics.lattice();
    int unlit = 0, lit = 0, disagreements = 0;
    for (const CellIndex cell : {CellIndex{0, 0}, CellIndex{2, 2}, CellIndex{5, 3}}) {
        const Eigen::Vector2d h = lattice.center(cell);
        for (int iy = -11; iy <= 11; ++iy)
            for (int ix = -9; ix <= 9; ++ix) {
                const Eigen::Vector2d p(ix * 0.21, iy * 0.215);
                const Eigen::Vector2d s = p / cd.b;
                // (y_A, u_A) = ac^-1 (h, s) per axis.
                bool inside = true;
                std::array<Eigen::Vector2d, 2> at_a;  // y_A, u_A
                const double det = ac.determinant();
                for (int axis = 0; axis < 2; ++axis) {
                    const double y = h[axis], u = s[axis];
                    at_a[0][axis] = (ac.d * y - ac.b * u) / det;
                    at_a[1][axis] = (-ac.c * y + ac.a * u) / det;
                }
                for (std::size_t k = 0; k < c; ++k) {
                    const RayMatrix m = k == 0 ? RayMatrix{} : vertex_matrix(system, 0, k - 1);
                    const double z_gap = k == 0 ? 0.0 : system.surfaces[k].z - system.surfaces[k - 1].z;
                    const RayMatrix to_k = translation(z_gap) * m;
                    Eigen::Vector2d y;
                    for (int axis = 0; axis < 2; ++axis) y[axis] = to_k.apply(at_a[0][axis], at_a[1][axis])[0];
                    const double semi = std::get<CircularAperture>(system.surfaces[k].aperture).semi_diameter;
                    inside = inside && y.norm() <= semi * (1 + kApertureTolerance);
                }
                const DotRay ray = meso.dot(p, cell, Model::Paraxial);
                if (ray.light == DotLight::Crossed) continue;  // tested below
                (inside ? lit : unlit)++;
                disagreements += (ray.light == DotLight::Lit) != inside;
            }
    }
    EXPECT_EQ(disagreements, 0);
    EXPECT_GT(unlit, 100);
    EXPECT_GT(lit, 3 * unlit / 2);
}

TEST(MesoPixel, DotsWhoseRayLeavesThroughANeighbourAreCrossed) {
    // Behind the pattern the chief ray keeps spreading away from the cell's axis: at the
    // pair's back surface its height is B_c8 s = (B_c8 / B_cd) p, so dots beyond
    // p = (pitch/2) B_cd / B_c8 leave through the neighbouring lenslet (crosstalk).
    const DesignOptics optics(bundled_design(3));
    const MesoPixelOptics meso(optics);
    const SequentialSystem& system = optics.system();
    const std::size_t back = meso.pattern_surface() + 1;
    ASSERT_EQ(system.surfaces[back].label, "D back");
    const double b_cd = vertex_matrix(system, meso.meso_front(), meso.pattern_surface()).b;
    const double b_c8 = (translation(system.surfaces[back].z - system.surfaces[back - 1].z) *
                         vertex_matrix(system, meso.meso_front(), back - 1)).b;
    const double edge = 0.5 * optics.lattice().pitch_x() * b_cd / b_c8;
    EXPECT_GT(edge, 1.8);  // a thin strip of the 2 mm half-cell
    EXPECT_LT(edge, 2.0);
    const CellIndex cell{2, 2};
    for (const double sign : {-1.0, 1.0}) {
        EXPECT_EQ(meso.dot({sign * (edge - 1e-6), 0.1}, cell, Model::Paraxial).light, DotLight::Lit);
        const DotRay crossed = meso.dot({sign * (edge + 1e-6), 0.1}, cell, Model::Paraxial);
        EXPECT_EQ(crossed.light, DotLight::Crossed);
        EXPECT_EQ(crossed.status, RayStatus::CrossedCell);
        EXPECT_EQ(crossed.surface, static_cast<int>(back));
    }
}

TEST(MesoPixel, ExactMatchesParaxialNearTheAxisAndPartsAtTheCellEdge) {
    const DesignOptics optics(bundled_design(3));
    const MesoPixelOptics meso(optics);
    const CellIndex cell{3, 2};
    const Eigen::Vector2d tiny(1e-3, -5e-4);
    const DotRay p = meso.dot(tiny, cell, Model::Paraxial), e = meso.dot(tiny, cell, Model::Exact);
    ASSERT_EQ(e.light, DotLight::Lit);
    EXPECT_LT((slopes(e.output) - slopes(p.output)).norm(), 1e-3 * slopes(p.output).norm());
    const Eigen::Vector2d edge(1.9, 0.0);
    const DotRay pe = meso.dot(edge, cell, Model::Paraxial), ee = meso.dot(edge, cell, Model::Exact);
    ASSERT_EQ(ee.light, DotLight::Lit);
    const double error_deg = radians_to_degrees(angle_between(pe.output, ee.output));
    EXPECT_GT(error_deg, 0.01);  // aberration: the exact model is worth its cost here
    EXPECT_LT(error_deg, 0.5);
}

TEST(MesoPixel, OffsetForInvertsTheOutputMapInBothModels) {
    const DesignOptics optics(bundled_design(3));
    const MesoPixelOptics meso(optics);
    const CellIndex cell{1, 3};
    for (const Model model : {Model::Paraxial, Model::Exact})
        for (const Eigen::Vector2d& p : {Eigen::Vector2d(0.4, -1.2), Eigen::Vector2d(-1.5, 0.6)}) {
            const DotRay ray = meso.dot(p, cell, model);
            ASSERT_EQ(ray.light, DotLight::Lit);
            const auto back = meso.offset_for(ray.output, cell, model);
            ASSERT_TRUE(back.has_value()) << to_string(model);
            EXPECT_NEAR((*back - p).norm(), 0.0, 1e-7) << to_string(model);
        }
}

TEST(MesoPixel, BinSamplesLandInTheirMesoCell) {
    const DesignOptics optics(bundled_design(3));
    const MesoPixelOptics meso(optics);
    const double b = optics.paraxial_b();
    for (const CellIndex cell : {CellIndex{0, 0}, CellIndex{3, 2}, CellIndex{5, 4}}) {
        const IncidentBin paraxial = meso.bin(cell, Model::Paraxial, 3);
        // Closed form: the chief ray through the main lens's centre lands at B tan.
        const Eigen::Vector2d h = optics.lattice().center(cell);
        EXPECT_NEAR((slopes(paraxial.centre) - h / b).norm(), 0.0, 1e-12);
        auto angle_to = [&](double x) {
            return radians_to_degrees(angle_between(paraxial.centre, Eigen::Vector3d(x / b, h.y() / b, 1).normalized()));
        };
        EXPECT_NEAR(paraxial.half_width_x_deg, 0.5 * (angle_to(h.x() - 2.0) + angle_to(h.x() + 2.0)), 1e-7);
        const IncidentBin exact = meso.bin(cell, Model::Exact, 3);
        // The field lens (30 mm) vignettes the outer corner of the corner bins (the thesis's
        // "3" and "7" in figure 8.13): those samples have no exact chief ray.
        if (cell == CellIndex{3, 2}) {
            EXPECT_EQ(exact.samples.size(), 9u);
        } else {
            EXPECT_GE(exact.samples.size(), 4u);
            EXPECT_LT(exact.samples.size(), 9u);
        }
        for (const auto& d : exact.samples) {
            const auto landing = optics.land(d, cell, Model::Exact);
            EXPECT_EQ(landing.status, RayStatus::Ok);
            EXPECT_EQ(landing.cell, cell);
        }
        EXPECT_GT(exact.half_width_x_deg, 1.5);
    }
}

TEST(MesoPixel, ObserverInvariantDesignsAreRejected) {
    const DesignOptics optics(bundled_design(1));
    try {
        const MesoPixelOptics meso(optics);
        FAIL() << "Design I accepted";
    } catch (const InputError& error) {
        EXPECT_THAT(error.what(), HasSubstr("Design III or IV"));
        EXPECT_THAT(error.what(), HasSubstr("design1.toml"));
    }
}

}  // namespace
}  // namespace rfd::optics
