// The paraxial engine against closed forms: catalogue lenses, the lensmaker's and
// Gullstrand's equations, conjugates, and the augmented matrices of decentred lenslets.

#include <cmath>

#include <gtest/gtest.h>

#include "optics/lens_file.hpp"
#include "optics/paraxial.hpp"

namespace rfd::optics {
namespace {

constexpr double kR = 25.8, kT = 5.3, kN = 1.5168;

// Single refracting surfaces built by hand, so the closed forms below stay independent of
// the lens-file reader (which has its own test at the end).
SequentialSystem plano_convex(bool curved_first) {
    SequentialSystem s;
    if (curved_first) {
        s.surfaces.push_back({Conic{1 / kR}, CircularAperture{12.5}, 0.0, kN, "curved"});
        s.surfaces.push_back({Flat{}, CircularAperture{12.5}, kT, 1.0, "flat"});
    } else {
        s.surfaces.push_back({Flat{}, CircularAperture{12.5}, 0.0, kN, "flat"});
        s.surfaces.push_back({Conic{-1 / kR}, CircularAperture{12.5}, kT, 1.0, "curved"});
    }
    return s;
}

TEST(Paraxial, PlanoConvexCurvedSideFirstCatalogueValues) {
    // Edmund-style N-BK7 PCX: EFL = R/(n-1) = 49.9226, BFL = EFL - t/n = 46.4284.
    const auto p = cardinal_points(plano_convex(true));
    EXPECT_NEAR(p.efl, 49.9226, 5e-5);
    EXPECT_NEAR(p.bfl, 49.9226 - kT / kN, 5e-5);
    EXPECT_NEAR(p.bfl, 46.4284, 5e-5);
    EXPECT_NEAR(p.matrix.determinant(), 1.0, 1e-12);
    // Curved side first: the front principal plane is at the curved vertex, the rear one
    // inside the glass, t/n in front of the flat.
    EXPECT_NEAR(p.front_principal_z, 0.0, 1e-12);
    EXPECT_NEAR(p.rear_principal_z, kT - kT / kN, 1e-12);
}

TEST(Paraxial, PlanoConvexFlatSideFirst) {
    // Turned round: BFL = EFL, FFL = EFL - t/n, principal planes mirrored.
    const auto p = cardinal_points(plano_convex(false));
    EXPECT_NEAR(p.efl, kR / (kN - 1), 1e-12);
    EXPECT_NEAR(p.bfl, kR / (kN - 1), 1e-12);
    EXPECT_NEAR(p.ffl, kR / (kN - 1) - kT / kN, 1e-12);
    EXPECT_NEAR(p.rear_principal_z, kT, 1e-12);
}

TEST(Paraxial, ThickBiconvexLensMakersFormula) {
    const double r1 = 40.0, r2 = -60.0, t = 8.0, n = 1.6;
    SequentialSystem s;
    s.surfaces.push_back({Conic{1 / r1}, Unbounded{}, 0.0, n, "1"});
    s.surfaces.push_back({Conic{1 / r2}, Unbounded{}, t, 1.0, "2"});
    const double power = (n - 1) * (1 / r1 - 1 / r2 + (n - 1) * t / (n * r1 * r2));
    const auto p = cardinal_points(s);
    EXPECT_NEAR(p.efl, 1 / power, 1e-10);
    // Principal planes of a thick lens: h1 = -f (n-1) t / (n r2), h2 = -f (n-1) t / (n r1).
    EXPECT_NEAR(p.front_principal_z, -(1 / power) * (n - 1) * t / (n * r2), 1e-10);
    EXPECT_NEAR(p.rear_principal_z - t, -(1 / power) * (n - 1) * t / (n * r1), 1e-10);
}

TEST(Paraxial, TwoLensesBackToBackFollowGullstrand) {
    // Two identical PCX lenses, flat sides touching: powers P each, principal planes at
    // the curved vertices, separated by 2t inside glass of index n:
    // P_total = 2P - (2t/n) P^2, about half the focal length of one lens.
    SequentialSystem s;
    s.surfaces.push_back({Conic{1 / kR}, Unbounded{}, 0.0, kN, "front"});
    s.surfaces.push_back({Flat{}, Unbounded{}, kT, kN, "contact"});
    s.surfaces.push_back({Conic{-1 / kR}, Unbounded{}, 2 * kT, 1.0, "back"});
    const double p1 = (kN - 1) / kR;
    const double expected = 2 * p1 - (2 * kT / kN) * p1 * p1;
    const auto p = cardinal_points(s);
    EXPECT_NEAR(p.power, expected, 1e-14);
    EXPECT_NEAR(p.efl / (kR / (kN - 1)), 0.5, 0.05);
}

TEST(Paraxial, ConjugatesObeyTheGaussianEquationFromThePrincipalPlanes) {
    const auto p = cardinal_points(plano_convex(true));
    for (double object : {75.0, 2 * p.efl, 200.0, 1000.0}) {
        const auto image = conjugate(p, object);
        ASSERT_TRUE(image.has_value());
        const double s = object + (p.front_principal_z - p.first_vertex_z);     // to H
        const double s_image = image->image_distance + (p.last_vertex_z - p.rear_principal_z);  // from H'
        EXPECT_NEAR(1 / s + 1 / s_image, 1 / p.efl, 1e-12) << object;
        EXPECT_NEAR(image->magnification, -s_image / s, 1e-12);
    }
    EXPECT_NEAR(conjugate(p, 2 * p.efl - (p.front_principal_z - p.first_vertex_z))->magnification, -1.0, 1e-12);
    // An object in the front focal plane goes to infinity.
    EXPECT_FALSE(conjugate(p, p.ffl).has_value());
}

TEST(Paraxial, DeterminantIsTheRatioOfIndices) {
    SequentialSystem s;
    s.surfaces.push_back({Conic{1 / 10.0}, Unbounded{}, 0.0, 1.5, "into glass"});
    s.surfaces.push_back({Conic{-1 / 30.0}, Unbounded{}, 4.0, 1.33, "into water"});
    EXPECT_NEAR(vertex_matrix(s, 0, 1).determinant(), 1.0 / 1.33, 1e-14);
}

TEST(Paraxial, DecentredMatrixIsShiftMatrixShift) {
    const RayMatrix m = translation(3.0) * refraction(1 / 1.47, 1.0, 1.49);
    const double h = 0.73;
    const AffineRayMatrix shifted = decentred(m, h);
    // T(h) M T(-h): subtract h, apply M, add h back.
    for (double y : {-1.0, 0.0, 0.4, 2.0})
        for (double u : {-0.2, 0.0, 0.1}) {
            const auto local = m.apply(y - h, u);
            const auto got = shifted.apply(y, u);
            EXPECT_NEAR(got[0], local[0] + h, 1e-14);
            EXPECT_NEAR(got[1], local[1], 1e-14);
        }
    // Composition of augmented matrices matches applying them in turn.
    const AffineRayMatrix other = decentred(translation(1.5) * refraction(-1 / 2.0, 1.49, 1.0), -0.4);
    const AffineRayMatrix both = other * shifted;
    const auto in_turn = other.apply(shifted.apply(0.3, 0.05)[0], shifted.apply(0.3, 0.05)[1]);
    EXPECT_NEAR(both.apply(0.3, 0.05)[0], in_turn[0], 1e-14);
    EXPECT_NEAR(both.apply(0.3, 0.05)[1], in_turn[1], 1e-14);
}

TEST(Paraxial, RayThroughALensletVertexKeepsItsSlopeAtTheSurface) {
    // At a single refracting surface, the ray through the lenslet's own vertex meets the
    // surface along its normal's plane: only the index changes its slope (n1 u / n2).
    const AffineRayMatrix lenslet = decentred(refraction(1 / 1.47, 1.0, 1.49), 5.2);
    const auto out = lenslet.apply(5.2, 0.1);
    EXPECT_NEAR(out[0], 5.2, 1e-15);
    EXPECT_NEAR(out[1], 0.1 / 1.49, 1e-15);
}

TEST(Paraxial, LensFileReadsTheSameSystem) {
    const auto system = parse_lens_system(R"(
name = "PCX N-BK7"
[[surface]]
radius_mm = 25.8
thickness_mm = 5.3
index = 1.5168
semi_diameter_mm = 12.5
[[surface]]
radius = "flat"
material = "air"
semi_diameter_mm = 12.5
thickness_mm = 46.4284
)", "pcx.toml");
    ASSERT_EQ(system.surfaces.size(), 3u);  // the image plane is added
    EXPECT_EQ(system.surfaces[2].label, "image");
    EXPECT_NEAR(cardinal_points(system, 0, 1).efl, 49.9226, 5e-5);
}

}  // namespace
}  // namespace rfd::optics
