// The exact tracer: agreement with the paraxial engine in its limit, reversibility, the
// stable intersection, and a typed status (never NaN) wherever the models fail.

#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "optics/exact.hpp"
#include "optics/paraxial.hpp"
#include "optics/spot.hpp"

namespace rfd::optics {
namespace {

SequentialSystem with_image_plane(SequentialSystem s, double distance) {
    const double z = s.surfaces.back().z + distance;
    s.surfaces.push_back({Flat{}, Unbounded{}, z, s.surfaces.back().index_after, "image"});
    return s;
}

SequentialSystem pcx(bool curved_first) {
    SequentialSystem s;
    if (curved_first) {
        s.surfaces.push_back({Conic{1 / 25.8}, CircularAperture{12.5}, 0.0, 1.5168, "curved"});
        s.surfaces.push_back({Flat{}, CircularAperture{12.5}, 5.3, 1.0, "flat"});
    } else {
        s.surfaces.push_back({Flat{}, CircularAperture{12.5}, 0.0, 1.5168, "flat"});
        s.surfaces.push_back({Conic{-1 / 25.8}, CircularAperture{12.5}, 5.3, 1.0, "curved"});
    }
    return with_image_plane(s, 40.0);
}

SequentialSystem back_to_back_pair() {
    SequentialSystem s;
    s.surfaces.push_back({Conic{1 / 5.4915}, CircularAperture{2.0}, 0.0, 1.523, "front"});
    s.surfaces.push_back({Flat{}, CircularAperture{2.0}, 2.0, 1.523, "pattern"});
    s.surfaces.push_back({Conic{-1 / 5.4915}, CircularAperture{2.0}, 4.0, 1.0, "back"});
    return with_image_plane(s, 6.0);
}

SequentialSystem paraboloid() {
    SequentialSystem s;
    s.surfaces.push_back({Conic{1 / 20.0, -1.0}, CircularAperture{8.0}, 0.0, 1.6, "paraboloid"});
    s.surfaces.push_back({Flat{}, CircularAperture{8.0}, 4.0, 1.0, "flat"});
    return with_image_plane(s, 25.0);
}

// Design-I-like hexagonal array: curved front, flat back, pattern plane at focus.
SequentialSystem lenslet_array() {
    const Lattice lattice = Lattice::hexagonal(2.358, 9, 9);
    SequentialSystem s;
    s.surfaces.push_back({Conic{1 / 1.4751}, LatticeAperture{lattice}, 0.0, 1.4917, "A front"});
    s.surfaces.push_back({Flat{}, Unbounded{}, 2.0, 1.0, "A back"});
    const double focus = cardinal_points(s, 0, 1).rear_focal_z;
    s.surfaces.push_back({Flat{}, LatticeAperture{lattice}, focus, 1.0, "B pattern"});
    return s;
}

TEST(Exact, AgreesWithParaxialInTheParaxialLimit) {
    for (const auto& system : {pcx(true), pcx(false), back_to_back_pair(), paraboloid()}) {
        const std::size_t last = system.surfaces.size() - 1;
        for (double height : {1e-6, -3e-6}) {
            for (double angle : {1e-6, -2e-6}) {
                const Ray ray{{0.3 * height, height, -1.0},
                              Eigen::Vector3d(0.5 * angle, angle, 1.0).normalized()};
                const TraceResult exact = trace(system, ray);
                ASSERT_EQ(exact.status, RayStatus::Ok);
                const ParaxialResult paraxial = trace_paraxial(system, paraxial_from(ray), -1.0, 0, last);
                ASSERT_EQ(paraxial.status, RayStatus::Ok);
                const double ey = exact.ray.origin.y(), ety = exact.ray.direction.y() / exact.ray.direction.z();
                EXPECT_NEAR(ey, paraxial.ray.y, 1e-9 * std::abs(paraxial.ray.y)) << system.surfaces[0].label;
                EXPECT_NEAR(ety, paraxial.ray.ty, 1e-9 * std::abs(paraxial.ray.ty));
                EXPECT_NEAR(exact.ray.origin.x(), paraxial.ray.x, 1e-9 * std::abs(paraxial.ray.x));
            }
        }
    }
}

TEST(Exact, ReversingATraceReturnsToItsStart) {
    std::mt19937_64 random(11);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (const auto& system : {pcx(true), pcx(false), back_to_back_pair(), paraboloid()}) {
        const SequentialSystem back = reversed(system);
        const double semi = std::get<CircularAperture>(system.surfaces[0].aperture).semi_diameter;
        int checked = 0;
        for (int k = 0; k < 300; ++k) {
            const Eigen::Vector3d start(0.7 * semi * unit(random), 0.7 * semi * unit(random), -2.0);
            const Eigen::Vector3d d = Eigen::Vector3d(0.1 * unit(random), 0.1 * unit(random), 1.0).normalized();
            const TraceResult forward = trace(system, Ray{start, d});
            if (forward.status != RayStatus::Ok) continue;
            // Mirror into the reversed frame: z -> -z, and send the ray back.
            const Eigen::Vector3d o(forward.ray.origin.x(), forward.ray.origin.y(), -forward.ray.origin.z());
            const Eigen::Vector3d r(-forward.ray.direction.x(), -forward.ray.direction.y(), forward.ray.direction.z());
            // Start a little before the reversed first surface (the image plane).
            const TraceResult home = trace(back, Ray{o - 1e-3 * r, r}, 1, back.surfaces.size() - 1);
            ASSERT_EQ(home.status, RayStatus::Ok);
            // Back on the line it came in on: its distance from that line is tiny.
            const Eigen::Vector3d p(home.ray.origin.x(), home.ray.origin.y(), -home.ray.origin.z());
            const Eigen::Vector3d dir(-home.ray.direction.x(), -home.ray.direction.y(), home.ray.direction.z());
            EXPECT_NEAR((p - start).cross(d).norm(), 0.0, 1e-9);
            EXPECT_NEAR((dir - d).norm(), 0.0, 1e-12);
            ++checked;
        }
        EXPECT_GT(checked, 200);
    }
}

TEST(Exact, IntersectionLiesOnTheSurfaceAndMatchesBisection) {
    std::mt19937_64 random(5);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (const Profile& profile : {Profile(Conic{1 / 5.0}), Profile(Conic{-1 / 8.0}),
                                   Profile(Conic{1 / 6.0, -1.0}), Profile(Conic{1 / 6.0, -2.5}),
                                   Profile(Conic{1 / 6.0, 0.8}), Profile(Flat{})}) {
        for (int k = 0; k < 2000; ++k) {
            const Eigen::Vector3d o(2.5 * unit(random), 2.5 * unit(random), -3.0);
            const Eigen::Vector3d d = Eigen::Vector3d(0.3 * unit(random), 0.3 * unit(random), 1.0).normalized();
            const auto t = intersect(profile, o, d, 0.0);
            if (!t) continue;
            const Eigen::Vector3d p = o + *t * d;
            const auto s = sag(profile, p.head<2>().squaredNorm());
            ASSERT_TRUE(s.has_value());
            EXPECT_NEAR(p.z(), *s, 1e-12);
            // Independent root: bisection on f(t) = z(t) - sag(r(t)), which changes sign
            // from the start (in front of the surface) to the hit.
            auto f = [&](double tt) {
                const Eigen::Vector3d q = o + tt * d;
                return q.z() - sag(profile, q.head<2>().squaredNorm()).value_or(1e9);
            };
            double lo = 0.0, hi = *t + 1e-9;
            if (f(lo) < 0 && f(hi) > 0) {
                for (int i = 0; i < 200; ++i) {
                    const double mid = 0.5 * (lo + hi);
                    (f(mid) < 0 ? lo : hi) = mid;
                }
                EXPECT_NEAR(0.5 * (lo + hi), *t, 1e-9);
            }
        }
    }
}

TEST(Exact, ARayStartingOnASurfaceNeverHitsItAgain) {
    std::mt19937_64 random(9);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (const Profile& profile : {Profile(Conic{1 / 5.0}), Profile(Conic{-1 / 5.0}),
                                   Profile(Conic{1 / 4.0, -1.0}), Profile(Flat{})}) {
        for (int k = 0; k < 5000; ++k) {
            const double x = 2.0 * unit(random), y = 2.0 * unit(random);
            const Eigen::Vector3d on(x, y, sag(profile, x * x + y * y).value());
            const Eigen::Vector3d in = Eigen::Vector3d(0.4 * unit(random), 0.4 * unit(random), 1.0).normalized();
            const auto out = refract(in, normal_at(profile, on), 1.0 / 1.5);
            ASSERT_TRUE(out.has_value());
            const auto again = intersect(profile, on, *out, 0.0);
            // No hit at the starting point; any later hit is a real second crossing far away.
            if (again) {
                EXPECT_GT(*again, 1e-6);
            }
        }
    }
}

TEST(Exact, SteepAnglesGiveStatusesNotNaN) {
    const SequentialSystem system = pcx(false);  // flat side first
    int tir = 0;
    for (double angle = 60.0; angle < 89.95; angle += 0.5) {
        const double th = angle * 3.14159265358979 / 180.0;
        for (double h : {-10.0, 0.0, 10.0}) {
            const Ray ray{{0.0, h - std::tan(th), -1.0}, {0.0, std::sin(th), std::cos(th)}};
            const TraceResult r = trace(system, ray);
            EXPECT_TRUE(r.ray.origin.allFinite());
            EXPECT_TRUE(r.ray.direction.allFinite());
            EXPECT_NEAR(r.ray.direction.norm(), 1.0, 1e-12);
            if (r.status == RayStatus::TotalInternalReflection) ++tir;
        }
    }
    EXPECT_GT(tir, 0);  // rays at the rim of the curved exit, steeply inside the glass
}

TEST(Exact, TotalInternalReflectionAtAFlatExit) {
    // Inside glass of n = 1.5 the critical angle is asin(1/1.5) = 41.8 degrees.
    SequentialSystem s;
    s.index_before = 1.5;
    s.surfaces.push_back({Flat{}, Unbounded{}, 0.0, 1.0, "exit"});
    const auto at = [&](double degrees) {
        const double th = degrees * 3.14159265358979 / 180.0;
        return trace(s, Ray{{0, 0, -1}, {std::sin(th), 0, std::cos(th)}}).status;
    };
    EXPECT_EQ(at(41.0), RayStatus::Ok);
    EXPECT_EQ(at(42.5), RayStatus::TotalInternalReflection);
}

TEST(Exact, OutsideTheApertureIsVignetted) {
    const SequentialSystem system = pcx(true);
    const TraceResult inside = trace(system, Ray{{0, 12.49, -1}, {0, 0, 1}});
    const TraceResult outside = trace(system, Ray{{0, 12.6, -1}, {0, 0, 1}});
    EXPECT_EQ(inside.status, RayStatus::Ok);
    EXPECT_EQ(outside.status, RayStatus::Vignetted);
    EXPECT_EQ(outside.surface, 0);
    // The documented tolerance: a ray aimed exactly at the rim of the flat back passes.
    SequentialSystem flat;
    flat.surfaces.push_back({Flat{}, CircularAperture{2.0}, 0.0, 1.0, "stop"});
    EXPECT_EQ(trace(flat, Ray{{2.0, 0, -1}, {0, 0, 1}}).status, RayStatus::Ok);
    EXPECT_EQ(trace(flat, Ray{{2.0 * (1 + 1e-7), 0, -1}, {0, 0, 1}}).status, RayStatus::Vignetted);
}

TEST(Exact, LensletArrayReportsItsCellAndWrapOver) {
    const SequentialSystem system = lenslet_array();
    const Lattice& lattice = *system.lattice();
    std::mt19937_64 random(3);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    const Eigen::Vector2d half = lattice.half_extent();
    int on_axis = 0;
    for (int k = 0; k < 5000; ++k) {
        // Normal incidence: every ray stays under the lenslet it entered.
        const Eigen::Vector2d p(0.8 * half.x() * unit(random), 0.8 * half.y() * unit(random));
        const TraceResult r = trace(system, Ray{{p.x(), p.y(), -1.0}, {0, 0, 1}});
        ASSERT_EQ(r.status, RayStatus::Ok);
        ASSERT_TRUE(r.has_cell);
        // The cell is the one whose cap the ray met: for a vertical ray, the cell under it.
        EXPECT_EQ(r.cell, lattice.cell_at(p));
        ++on_axis;
    }
    EXPECT_EQ(on_axis, 5000);
    // Aimed through a lenslet's vertex at an angle: inside the cell up to about
    // atan((pitch/2) / f) = 21.5 degrees along x, crossing beyond.
    const CellIndex centre = lattice.cell_at({0, 0});
    const Eigen::Vector2d c = lattice.center(centre);
    auto through_vertex = [&](double degrees) {
        const double th = degrees * 3.14159265358979 / 180.0;
        const Eigen::Vector3d d(std::sin(th), 0, std::cos(th));
        return trace(system, Ray{Eigen::Vector3d(c.x(), c.y(), 0.0) - d / d.z(), d});
    };
    EXPECT_EQ(through_vertex(15.0).status, RayStatus::Ok);
    const TraceResult steep = through_vertex(30.0);
    EXPECT_EQ(steep.status, RayStatus::CrossedCell);
    EXPECT_EQ(steep.surface, 2);
    EXPECT_EQ(steep.cell, centre);  // the lenslet it entered
    // Outside the array: vignetted at the first surface.
    const TraceResult away = trace(system, Ray{{half.x() + 3.0, 0, -1}, {0, 0, 1}});
    EXPECT_EQ(away.status, RayStatus::Vignetted);
}

TEST(Exact, SteepRaysMeetTheNeighbouringCapFirst) {
    // A ray grazing across the array at 70 degrees meets a cap side before reaching the
    // cell below its vertex-plane crossing; the hit must lie on the cap of its own cell.
    const SequentialSystem system = lenslet_array();
    const Lattice& lattice = *system.lattice();
    std::mt19937_64 random(4);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (int k = 0; k < 2000; ++k) {
        const double th = (60.0 + 25.0 * std::abs(unit(random))) * 3.14159265358979 / 180.0;
        const double ph = 3.14159265358979 * unit(random);
        const Eigen::Vector3d d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
        const Eigen::Vector3d o(3.0 * unit(random), 3.0 * unit(random), -0.01);
        const TraceResult r = trace(system, Ray{o - d * (1.0 / d.z()), d}, 0, 0);
        EXPECT_TRUE(r.ray.origin.allFinite());
        if (r.status != RayStatus::Ok) continue;
        const Eigen::Vector2d centre = lattice.center(r.cell);
        const Eigen::Vector3d local = r.ray.origin - Eigen::Vector3d(centre.x(), centre.y(), 0.0);
        EXPECT_TRUE(lattice.cell_contains(r.cell, r.ray.origin.head<2>()));
        EXPECT_NEAR(local.z(), sag(system.surfaces[0].profile, local.head<2>().squaredNorm()).value(), 1e-9);
    }
}

TEST(Exact, BatchMatchesSingleRays) {
    const SequentialSystem system = lenslet_array();
    std::mt19937_64 random(8);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    RayBatch batch;
    batch.resize(20000);
    std::vector<Ray> rays;
    for (std::size_t k = 0; k < batch.size(); ++k) {
        rays.push_back(Ray{{9 * unit(random), 9 * unit(random), -1.0},
                           Eigen::Vector3d(0.5 * unit(random), 0.5 * unit(random), 1.0).normalized()});
        batch.set(k, rays.back());
    }
    trace_batch(system, batch, 0, 2);
    const auto counts = count_statuses(batch);
    std::size_t total = 0;
    for (std::size_t k = 0; k < batch.size(); ++k) {
        const TraceResult single = trace(system, rays[k], 0, 2);
        EXPECT_EQ(batch.status[k], single.status);
        EXPECT_EQ(batch.get(k).origin, single.ray.origin);
        EXPECT_EQ(batch.cell_i[k], single.cell.i);
    }
    for (auto n : counts) total += n;
    EXPECT_EQ(total, batch.size());
    EXPECT_GT(counts[static_cast<std::size_t>(RayStatus::CrossedCell)], 0u);
}

TEST(Exact, ParaxialBatchMatchesSingleRays) {
    const SequentialSystem system = lenslet_array();
    ParaxialBatch batch;
    batch.resize(1000);
    std::vector<ParaxialRay> rays;
    std::mt19937_64 random(12);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (std::size_t k = 0; k < batch.size(); ++k) {
        rays.push_back({9 * unit(random), 9 * unit(random), 0.4 * unit(random), 0.4 * unit(random)});
        batch.x[k] = rays[k].x;
        batch.y[k] = rays[k].y;
        batch.tx[k] = rays[k].tx;
        batch.ty[k] = rays[k].ty;
    }
    trace_paraxial_batch(system, batch, -1.0, 0, 2);
    for (std::size_t k = 0; k < batch.size(); ++k) {
        const ParaxialResult single = trace_paraxial(system, rays[k], -1.0, 0, 2);
        EXPECT_EQ(batch.status[k], single.status);
        EXPECT_EQ(batch.x[k], single.ray.x);
        EXPECT_EQ(batch.ty[k], single.ray.ty);
    }
}

TEST(Exact, SpotReportOfAPlanoConvexLens) {
    const SequentialSystem system = pcx(true);
    const SpotReport on_axis = spot_report(system, 0.0, 3.0, 2000);
    EXPECT_NEAR(on_axis.chief_height_exact, 0.0, 1e-12);
    EXPECT_GT(on_axis.rms_spot_radius, 0.0);
    // Spherical aberration grows with the cube of the aperture: the RMS spot of a pupil
    // twice as large is about eight times larger.
    const SpotReport wide = spot_report(system, 0.0, 6.0, 2000);
    EXPECT_NEAR(wide.rms_spot_radius / on_axis.rms_spot_radius, 8.0, 0.8);
    const SpotReport tilted = spot_report(system, 1.0, 3.0, 200);
    EXPECT_NEAR(tilted.chief_height_exact, tilted.chief_height_paraxial, 1e-3);
}

}  // namespace
}  // namespace rfd::optics

namespace rfd::optics {
namespace {

TEST(Exact, FresnelTransmittanceOfAGlassSlab) {
    // Normal incidence: T = 1 - ((n-1)/(n+1))^2 per face, two faces.
    SequentialSystem slab;
    slab.surfaces.push_back({Flat{}, Unbounded{}, 0.0, 1.5, "in"});
    slab.surfaces.push_back({Flat{}, Unbounded{}, 3.0, 1.0, "out"});
    const double face = 1.0 - 0.04;
    EXPECT_NEAR(trace(slab, Ray{{0, 0, -1}, {0, 0, 1}}).transmittance, face * face, 1e-12);
    // At Brewster's angle (atan 1.5) the p wave passes whole: T = 1 - Rs/2.
    const double brewster = std::atan(1.5);
    const double ci = std::cos(brewster), ct = std::sin(brewster);  // theta_t = 90 deg - theta_b
    const double rs = (ci - 1.5 * ct) / (ci + 1.5 * ct);
    EXPECT_NEAR(fresnel_transmittance(ci, ct, 1.0, 1.5), 1.0 - 0.5 * rs * rs, 1e-12);
    // Energy is the same both ways through an interface (reciprocity).
    EXPECT_NEAR(fresnel_transmittance(ci, ct, 1.0, 1.5), fresnel_transmittance(ct, ci, 1.5, 1.0), 1e-12);
}

}  // namespace
}  // namespace rfd::optics

namespace rfd::optics {
namespace {

TEST(Exact, GrazingRaysOnALensletArrayEndQuickly) {
    // Near 90 degrees the ray's path through the slab of caps spans an enormous stretch
    // of lattice; the trace must stay bounded by the array and give a status.
    const Lattice lattice = Lattice::hexagonal(2.358, 9, 9);
    SequentialSystem s;
    s.surfaces.push_back({Conic{1 / 1.4751}, LatticeAperture{lattice}, 0.0, 1.4917, "A front"});
    s.surfaces.push_back({Flat{}, Unbounded{}, 2.0, 1.0, "A back"});
    for (double degrees : {85.0, 89.0, 89.9, 89.99, 89.999, 89.9999}) {
        const double th = degrees * 3.14159265358979 / 180.0, ph = 3.14159265358979 / 4;
        const Eigen::Vector3d d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
        const TraceResult r = trace(s, Ray{Eigen::Vector3d(0, 0, 0.1) - d * (0.2 / d.z()), d});
        EXPECT_TRUE(r.ray.origin.allFinite()) << degrees;
        EXPECT_NE(r.status, RayStatus::CrossedCell) << degrees;
    }
}

}  // namespace
}  // namespace rfd::optics
