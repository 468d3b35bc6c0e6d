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

TEST(Paraxial, DeterminantIsTheRatioOfIndices) {
    SequentialSystem s;
    s.surfaces.push_back({Conic{1 / 10.0}, Unbounded{}, 0.0, 1.5, "into glass"});
    s.surfaces.push_back({Conic{-1 / 30.0}, Unbounded{}, 4.0, 1.33, "into water"});
    EXPECT_NEAR(vertex_matrix(s, 0, 1).determinant(), 1.0 / 1.33, 1e-14);
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

TEST(Paraxial, PlanoConvexMatricesAndCardinalPointsByHand) {
    // f = R/(n-1), P = (n-1)/R. Curved side first, M = R_flat T(t) R_curved:
    //   R_curved = [[1, 0], [-(n-1)/(nR), 1/n]], T(t) = [[1, t], [0, 1]], R_flat = [[1, 0], [0, n]]
    //   M = [[1 - t(n-1)/(nR), t/n], [-(n-1)/R, 1]]
    // BFL = -A/C = f - t/n, FFL = -D/C = f: F at -f, H = F + f = 0 (the curved vertex),
    // F' at t + f - t/n, H' = F' - f = t - t/n (t/n in front of the flat).
    const double f = kR / (kN - 1);
    const auto curved = cardinal_points(plano_convex(true));
    EXPECT_NEAR(curved.matrix.a, 1 - kT * (kN - 1) / (kN * kR), 1e-15);
    EXPECT_NEAR(curved.matrix.b, kT / kN, 1e-15);
    EXPECT_NEAR(curved.matrix.c, -(kN - 1) / kR, 1e-15);
    EXPECT_NEAR(curved.matrix.d, 1.0, 1e-15);
    EXPECT_NEAR(curved.matrix.determinant(), 1.0, 1e-12);
    EXPECT_NEAR(curved.efl, f, 1e-12);
    EXPECT_NEAR(curved.ffl, f, 1e-12);
    EXPECT_NEAR(curved.bfl, f - kT / kN, 1e-12);
    EXPECT_NEAR(curved.bfl, 46.4284, 5e-5);  // the catalogue's N-BK7 PCX: EFL 49.9226, BFL 46.4284
    EXPECT_NEAR(curved.front_focal_z, -f, 1e-12);
    EXPECT_NEAR(curved.front_principal_z, 0.0, 1e-12);
    EXPECT_NEAR(curved.rear_principal_z, kT - kT / kN, 1e-12);
    // Flat side first, M = R_curved' T(t) R_flat' with R_flat' = [[1, 0], [0, 1/n]] and
    // R_curved' (c = -1/R, n -> 1) = [[1, 0], [-(n-1)/R, n]]:
    //   M = [[1, t/n], [-(n-1)/R, 1 - t(n-1)/(nR)]]
    // BFL = f, FFL = f - t/n: H = -(f - t/n) + f = t/n (inside the glass), H' = t + f - f = t.
    const auto flat = cardinal_points(plano_convex(false));
    EXPECT_NEAR(flat.matrix.a, 1.0, 1e-15);
    EXPECT_NEAR(flat.matrix.b, kT / kN, 1e-15);
    EXPECT_NEAR(flat.matrix.c, -(kN - 1) / kR, 1e-15);
    EXPECT_NEAR(flat.matrix.d, 1 - kT * (kN - 1) / (kN * kR), 1e-15);
    EXPECT_NEAR(flat.efl, 49.9226, 5e-5);
    EXPECT_NEAR(flat.bfl, flat.efl, 1e-12);
    EXPECT_NEAR(flat.ffl, flat.efl - kT / kN, 1e-12);
    EXPECT_NEAR(flat.front_principal_z, kT / kN, 1e-12);
    EXPECT_NEAR(flat.rear_principal_z, kT, 1e-12);
    EXPECT_NEAR(flat.rear_focal_z, kT + f, 1e-12);
}

TEST(Paraxial, BackToBackPairIsGullstrandOfTheTwoLenses) {
    // Gullstrand for two thick lenses in air: P = P1 + P2 - (d/n0) P1 P2, with d the
    // distance from the first lens's rear principal plane H1' to the second's front one H2
    // and n0 = 1 (a zero air gap between the flats is no surface at all). Lens 1 (curved
    // first, z in [0, t]) has H1' = t - t/n; lens 2 (flat first, z in [t, 2t]) has
    // H2 = t + t/n: d = 2t/n and, with P1 = P2 = (n-1)/R, P = 2 P1 - (2t/n) P1^2.
    // The pair's principal planes: H = H1 + (d/n0) P2 / P, H' = H2' - (d/n0) P1 / P.
    SequentialSystem pair;
    pair.surfaces.push_back({Conic{1 / kR}, Unbounded{}, 0.0, kN, "front"});
    pair.surfaces.push_back({Flat{}, Unbounded{}, kT, kN, "contact"});
    pair.surfaces.push_back({Conic{-1 / kR}, Unbounded{}, 2 * kT, 1.0, "back"});
    const double p1 = (kN - 1) / kR, d = 2 * kT / kN;
    const double power = 2 * p1 - d * p1 * p1;
    const auto p = cardinal_points(pair);
    EXPECT_NEAR(p.efl, 1 / power, 1e-9);
    EXPECT_NEAR(p.front_principal_z, 0.0 + d * p1 / power, 1e-9);
    EXPECT_NEAR(p.rear_principal_z, 2 * kT - d * p1 / power, 1e-9);
    EXPECT_NEAR(p.bfl, p.efl - d * p1 / power, 1e-9);
    // About half the focal length of one lens, a little more because of d.
    EXPECT_GT(p.efl, 0.5 * kR / (kN - 1));
    EXPECT_LT(p.efl, 0.55 * kR / (kN - 1));
    // The same from the engine's own single-lens cardinal points.
    SequentialSystem second;
    second.surfaces.push_back({Flat{}, Unbounded{}, kT, kN, "flat"});
    second.surfaces.push_back({Conic{-1 / kR}, Unbounded{}, 2 * kT, 1.0, "curved"});
    const auto l1 = cardinal_points(plano_convex(true));
    const auto l2 = cardinal_points(second);
    const double gap = l2.front_principal_z - l1.rear_principal_z;
    EXPECT_NEAR(gap, d, 1e-12);
    EXPECT_NEAR(p.power, l1.power + l2.power - gap * l1.power * l2.power, 1e-15);
}

// A thick biconvex lens in air and a lens whose image space is water.
SequentialSystem biconvex() {
    SequentialSystem s;
    s.surfaces.push_back({Conic{1 / 40.0}, Unbounded{}, 0.0, 1.6, "1"});
    s.surfaces.push_back({Conic{-1 / 60.0}, Unbounded{}, 8.0, 1.0, "2"});
    return s;
}
SequentialSystem into_water() {
    SequentialSystem s;
    s.surfaces.push_back({Conic{1 / 30.0}, Unbounded{}, 2.0, 1.52, "glass"});
    s.surfaces.push_back({Conic{-1 / 45.0}, Unbounded{}, 7.0, 1.33, "water"});
    return s;
}

TEST(Paraxial, ConjugatesAgreeWithRaysTracedFromTheObjectPoint) {
    // Independent of conjugate()'s matrix algebra: two rays from an object point, traced
    // surface by surface, cross at the image; and the Gaussian equation from the principal
    // planes, n_in/s + n_out/s' = P with magnification -(n_in s')/(n_out s).
    for (const SequentialSystem& system : {plano_convex(true), plano_convex(false), biconvex(), into_water()}) {
        const auto p = cardinal_points(system);
        const std::size_t last = system.surfaces.size() - 1;
        for (double object : {2 * p.efl, 3 * p.efl, 1.5 * p.efl, 0.5 * p.efl, 10 * p.efl}) {
            const auto image = conjugate(p, object);
            ASSERT_TRUE(image.has_value());
            const double y0 = 1.0, z0 = p.first_vertex_z - object;
            const auto r1 = trace_paraxial(system, {0, y0, 0, 0.01}, z0, 0, last).ray;
            const auto r2 = trace_paraxial(system, {0, y0, 0, -0.02}, z0, 0, last).ray;
            const double s_image = -(r1.y - r2.y) / (r1.ty - r2.ty);
            const double y_image = r1.y + s_image * r1.ty;
            EXPECT_NEAR(image->image_distance, s_image, 1e-9 * std::abs(s_image)) << object;
            EXPECT_NEAR(image->magnification, y_image / y0, 1e-9) << object;
            const double s = p.first_vertex_z - object - p.front_principal_z;    // H - object, > 0
            const double s_prime = p.last_vertex_z + image->image_distance - p.rear_principal_z;
            EXPECT_NEAR(-p.n_in / s + p.n_out / s_prime, p.power, 1e-12) << object;
            EXPECT_NEAR(image->magnification, -(p.n_in * s_prime) / (p.n_out * -s), 1e-9) << object;
        }
        // An object at 2f from H images at 2f' behind H' with magnification -1 (n_in = n_out).
        if (p.n_in == p.n_out) {
            const auto at_2f = conjugate(p, 2 * p.efl - (p.front_principal_z - p.first_vertex_z));
            EXPECT_NEAR(at_2f->image_distance + p.last_vertex_z - p.rear_principal_z, 2 * p.efl, 1e-9);
            EXPECT_NEAR(at_2f->magnification, -1.0, 1e-12);
        }
    }
    // An object in the front focal plane goes to infinity.
    const auto pcx = cardinal_points(plano_convex(true));
    EXPECT_FALSE(conjugate(pcx, pcx.ffl).has_value());
}

TEST(Paraxial, DecentredIsTheComposedShiftMatrixShift) {
    // decentred(M, h) = T(h) M T(-h) with T(h) the augmented shift [[1 0 h] [0 1 0] [0 0 1]].
    const RayMatrix m = translation(2.0) * refraction(1 / 1.4751, 1.0, 1.4917);
    for (double h : {-7.1, 0.0, 0.73, 12.9}) {
        const AffineRayMatrix shift_in{RayMatrix{}, -h, 0.0};
        const AffineRayMatrix shift_out{RayMatrix{}, h, 0.0};
        const AffineRayMatrix composed = shift_out * (AffineRayMatrix{m, 0.0, 0.0} * shift_in);
        const AffineRayMatrix direct = decentred(m, h);
        EXPECT_NEAR(direct.m.a, composed.m.a, 1e-15);
        EXPECT_NEAR(direct.m.b, composed.m.b, 1e-15);
        EXPECT_NEAR(direct.m.c, composed.m.c, 1e-15);
        EXPECT_NEAR(direct.m.d, composed.m.d, 1e-15);
        EXPECT_NEAR(direct.e, composed.e, 1e-14);
        EXPECT_NEAR(direct.f, composed.f, 1e-15);
        // The lenslet's own axis (y = h, u = 0) is a ray of the decentred element.
        const auto axis = direct.apply(h, 0.0);
        EXPECT_NEAR(axis[0], h, 1e-14);
        EXPECT_NEAR(axis[1], 0.0, 1e-15);
    }
    // Composition of augmented matrices matches applying them in turn.
    const AffineRayMatrix first = decentred(m, 0.73);
    const AffineRayMatrix other = decentred(translation(1.5) * refraction(-1 / 2.0, 1.49, 1.0), -0.4);
    const AffineRayMatrix both = other * first;
    const auto in_turn = other.apply(first.apply(0.3, 0.05)[0], first.apply(0.3, 0.05)[1]);
    EXPECT_NEAR(both.apply(0.3, 0.05)[0], in_turn[0], 1e-14);
    EXPECT_NEAR(both.apply(0.3, 0.05)[1], in_turn[1], 1e-14);
}

// A hexagonal lenslet sheet (curved front, flat back) with the pattern plane at focus.
SequentialSystem lenslet_sheet(const Lattice& lattice) {
    SequentialSystem s;
    s.surfaces.push_back({Conic{1 / 1.47}, LatticeAperture{lattice}, 0.0, 1.4917, "front"});
    s.surfaces.push_back({Flat{}, Unbounded{}, 2.0, 1.0, "back"});
    const double focus = cardinal_points(s, 0, 1).rear_focal_z;
    s.surfaces.push_back({Flat{}, LatticeAperture{lattice}, focus, 1.0, "pattern"});
    return s;
}

TEST(Paraxial, EveryLensletFocusesOnItsOwnAxis) {
    const Lattice lattice = Lattice::hexagonal(2.358, 6, 5);
    const SequentialSystem s = lenslet_sheet(lattice);
    const double n = 1.4917;
    for (int j = 0; j < lattice.count_y(); ++j) {
        for (int i = 0; i < lattice.count_x(); ++i) {
            const Eigen::Vector2d c = lattice.center({i, j});
            // Parallel to the axis, off the lenslet's vertex: through its axis at the focus.
            const auto parallel = trace_paraxial(s, {c.x() + 0.3, c.y() - 0.2, 0, 0}, -1.0, 0, 2);
            ASSERT_EQ(parallel.status, RayStatus::Ok);
            EXPECT_EQ(parallel.cell, (CellIndex{i, j}));
            EXPECT_NEAR(parallel.ray.x, c.x(), 1e-12);
            EXPECT_NEAR(parallel.ray.y, c.y(), 1e-12);
            // Through the vertex: at the single refracting surface only the index acts
            // (n u is unchanged, no deviation by the lenslet's power) ...
            const double u = 0.05;
            const auto at_vertex = trace_paraxial(s, {c.x() - u, c.y() + 0.5 * u, u, -0.5 * u}, -1.0, 0, 0);
            EXPECT_NEAR(at_vertex.ray.x, c.x(), 1e-12);
            EXPECT_NEAR(n * at_vertex.ray.tx, u, 1e-15);
            EXPECT_NEAR(n * at_vertex.ray.ty, -0.5 * u, 1e-15);
            // ... and after the flat back the chief ray leaves parallel to itself (the
            // front nodal point of a plano-convex lens in air is its curved vertex).
            const auto chief = trace_paraxial(s, {c.x() - u, c.y() + 0.5 * u, u, -0.5 * u}, -1.0, 0, 1);
            EXPECT_NEAR(chief.ray.tx, u, 1e-15);
            EXPECT_NEAR(chief.ray.x, c.x() + 2.0 * u / n, 1e-12);
        }
    }
}

void expect_same_system(const SequentialSystem& a, const SequentialSystem& b) {
    ASSERT_EQ(a.surfaces.size(), b.surfaces.size());
    EXPECT_EQ(a.index_before, b.index_before);
    for (std::size_t k = 0; k < a.surfaces.size(); ++k) {
        const Surface &x = a.surfaces[k], &y = b.surfaces[k];
        EXPECT_EQ(x.profile.index(), y.profile.index());
        EXPECT_EQ(curvature_of(x.profile), curvature_of(y.profile));
        EXPECT_EQ(conic_of(x.profile), conic_of(y.profile));
        EXPECT_EQ(x.aperture.index(), y.aperture.index());
        EXPECT_EQ(x.z, y.z);
        EXPECT_EQ(x.index_after, y.index_after);
        EXPECT_EQ(x.label, y.label);
    }
}

TEST(Paraxial, ReversedSystemRoundTripsAndSwapsFrontAndBack) {
    SequentialSystem asphere;
    asphere.index_before = 1.2;
    asphere.surfaces.push_back({Conic{1 / 20.0, -1.0}, CircularAperture{8.0}, 0.0, 1.6, "parabola"});
    asphere.surfaces.push_back({Conic{-1 / 50.0, 0.4}, CircularAperture{8.0}, 4.0, 1.0, "ellipse"});
    for (const SequentialSystem& system : {plano_convex(true), biconvex(), into_water(), asphere,
                                           lenslet_sheet(Lattice::hexagonal(2.358, 4, 3))}) {
        const SequentialSystem back = reversed(system);
        back.validate();
        expect_same_system(reversed(back), system);
        // Mirror z -> -z: the front of one is the back of the other.
        const auto p = cardinal_points(system, 0, system.surfaces.size() - 1);
        const auto q = cardinal_points(back, 0, back.surfaces.size() - 1);
        EXPECT_NEAR(q.power, p.power, 1e-15);
        EXPECT_NEAR(q.n_in, p.n_out, 0.0);
        EXPECT_NEAR(q.bfl, p.ffl, 1e-9);
        EXPECT_NEAR(q.ffl, p.bfl, 1e-9);
        EXPECT_NEAR(q.rear_focal_length, p.front_focal_length, 1e-9);
        EXPECT_NEAR(q.front_principal_z, -p.rear_principal_z, 1e-9);
        EXPECT_NEAR(q.rear_principal_z, -p.front_principal_z, 1e-9);
        EXPECT_NEAR(q.matrix.determinant(), 1.0 / p.matrix.determinant(), 1e-14);
    }
}

}  // namespace
}  // namespace rfd::optics
