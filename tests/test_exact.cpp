// The exact tracer: agreement with the paraxial engine in its limit, reversibility, the
// stable intersection, and a typed status (never NaN) wherever the models fail.

#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <utility>

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
        int bisected = 0;
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
                ++bisected;
            }
        }
        EXPECT_GT(bisected, 1900);  // the comparison ran for nearly every ray
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

// The batch tracer runs stage by stage with masks (and, on AVX2 machines, in a clone
// compiled for them); every ray must come out bit for bit as the single-ray tracer has it,
// whichever way it ends.
TEST(Exact, ParaxialBatchMatchesSingleRays) {
    SequentialSystem rectangular = lenslet_array();
    const Lattice rect = Lattice::rectangular(2.1, 1.9, 8, 7);
    rectangular.surfaces[0].aperture = LatticeAperture{rect};
    rectangular.surfaces[2].aperture = LatticeAperture{rect};
    SequentialSystem stopped = pcx(true);
    stopped.surfaces.push_back({Flat{}, CircularAperture{12.0}, stopped.surfaces.back().z + 5.0, 1.0, "stop"});
    for (const SequentialSystem& system : {lenslet_array(), rectangular, stopped}) {
        const std::size_t last = system.surfaces.size() - 1;
        ParaxialBatch batch;
        batch.resize(3001);  // not a multiple of any block size
        std::vector<ParaxialRay> rays;
        std::mt19937_64 random(12);
        std::uniform_real_distribution<double> unit(-1.0, 1.0);
        for (std::size_t k = 0; k < batch.size(); ++k) {
            rays.push_back({13 * unit(random), 13 * unit(random), 0.4 * unit(random), 0.4 * unit(random)});
            batch.x[k] = rays[k].x;
            batch.y[k] = rays[k].y;
            batch.tx[k] = rays[k].tx;
            batch.ty[k] = rays[k].ty;
        }
        trace_paraxial_batch(system, batch, -1.0, 0, last);
        std::map<RayStatus, int> seen;
        for (std::size_t k = 0; k < batch.size(); ++k) {
            const ParaxialResult single = trace_paraxial(system, rays[k], -1.0, 0, last);
            ++seen[single.status];
            ASSERT_EQ(batch.status[k], single.status) << k;
            EXPECT_EQ(batch.x[k], single.ray.x);
            EXPECT_EQ(batch.y[k], single.ray.y);
            EXPECT_EQ(batch.tx[k], single.ray.tx);
            EXPECT_EQ(batch.ty[k], single.ray.ty);
            EXPECT_EQ(batch.cell_i[k], single.cell.i);
            EXPECT_EQ(batch.cell_j[k], single.cell.j);
        }
        // The rays cover every way a trace can end in this system.
        EXPECT_GT(seen[RayStatus::Ok], 100);
        EXPECT_GT(seen[RayStatus::Vignetted], 100);
        if (std::holds_alternative<LatticeAperture>(system.surfaces[0].aperture)) {
            EXPECT_GT(seen[RayStatus::CrossedCell], 100);
        }
    }
}

TEST(Exact, SpotReportOfAPlanoConvexLens) {
    const SequentialSystem system = pcx(true);
    const SpotReport on_axis = spot_report(system, 0.0, 3.0, 2000);
    ASSERT_TRUE(on_axis.chief_height_exact && on_axis.rms_spot_radius);
    EXPECT_NEAR(*on_axis.chief_height_exact, 0.0, 1e-12);
    EXPECT_GT(*on_axis.rms_spot_radius, 0.0);
    // Spherical aberration grows with the cube of the aperture: the RMS spot of a pupil
    // twice as large is about eight times larger.
    const SpotReport wide = spot_report(system, 0.0, 6.0, 2000);
    EXPECT_NEAR(*wide.rms_spot_radius / *on_axis.rms_spot_radius, 8.0, 0.8);
    const SpotReport tilted = spot_report(system, 1.0, 3.0, 200);
    ASSERT_TRUE(tilted.chief_height_exact);
    EXPECT_NEAR(*tilted.chief_height_exact, tilted.chief_height_paraxial, 1e-3);
}

TEST(Exact, SpotPupilGridKeepsTheRimAndItsSymmetry) {
    // The grid's points are (2i - n) / n times the pupil radius for i = 0..n (n = side - 1):
    // counted in integers, the disc holds those with (2i - n)^2 + (2j - n)^2 <= n^2, the
    // rim's points included; a floating-point test dropped some of them (1253 of 1257 at a
    // 2.5 mm pupil), leaving the grid lopsided.
    const SequentialSystem system = pcx(true);
    const std::pair<double, int> grids[] = {{2.5, 1320}, {3.0, 2000}, {1.7, 500}};
    for (const auto& [pupil, rays] : grids) {
        const SpotReport report = spot_report(system, 0.0, pupil, rays);
        const long side = std::lround(std::sqrt(rays * 4.0 / std::numbers::pi)), n = side - 1;
        std::size_t inside = 0;
        for (long i = 0; i <= n; ++i)
            for (long j = 0; j <= n; ++j)
                if ((2 * i - n) * (2 * i - n) + (2 * j - n) * (2 * j - n) <= n * n) ++inside;
        EXPECT_EQ(report.rays_traced, inside) << pupil << " mm, " << rays << " rays";
        // On the axis a symmetric grid has its centroid on the axis.
        ASSERT_TRUE(report.centroid_y);
        EXPECT_NEAR(*report.centroid_y, 0.0, 1e-12);
    }
}

TEST(Exact, SpotReportSaysWhenNoRayArrives) {
    // Far beyond the lens's field every ray of the pupil misses its aperture: no spot, and
    // no NaN standing in for one.
    const SequentialSystem system = pcx(true);
    const SpotReport report = spot_report(system, 89.9, 12.0, 200);
    EXPECT_EQ(report.status_counts[static_cast<std::size_t>(RayStatus::Ok)], 0u);
    EXPECT_FALSE(report.rms_spot_radius);
    EXPECT_FALSE(report.centroid_y);
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

namespace rfd::optics {
namespace {

constexpr double kPiExact = 3.14159265358979323846;

Eigen::Vector3d direction_at(double theta, double phi) {
    return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// A ray whose straight line passes through `point` with direction d, started one unit of
// z in front of it.
Ray ray_through(const Eigen::Vector3d& point, const Eigen::Vector3d& d) {
    return Ray{point - d / d.z(), d};
}

TEST(Exact, AgreesWithParaxialOnDecentredLenslets) {
    // Every lenslet of the array, in its own frame: rays 1e-5 mm from its vertex at slopes
    // of 1e-5 land on the pattern plane (flat: the same plane in both models) where the
    // augmented matrices put them, to 1e-9 of the local height and slope. Third-order
    // terms are (1e-5 / R)^2 ~ 5e-11 relative; rounding of the ~10 mm centres ~ 3e-10.
    const SequentialSystem system = lenslet_array();
    const Lattice& lattice = *system.lattice();
    const double scale = 1e-5;
    for (int j = 0; j < lattice.count_y(); ++j) {
        for (int i = 0; i < lattice.count_x(); ++i) {
            const Eigen::Vector2d c = lattice.center({i, j});
            for (const auto& [h, a] : {std::pair{1.0, 1.0}, {-3.0, 2.0}, {2.0, -1.5}}) {
                const double lx = 0.4 * h * scale, ly = h * scale, ux = 0.5 * a * scale, uy = a * scale;
                const Ray ray{{c.x() + lx - ux, c.y() + ly - uy, -1.0}, Eigen::Vector3d(ux, uy, 1.0).normalized()};
                const TraceResult exact = trace(system, ray);
                const ParaxialResult paraxial = trace_paraxial(system, paraxial_from(ray), -1.0, 0, 2);
                ASSERT_EQ(exact.status, RayStatus::Ok);
                ASSERT_EQ(paraxial.status, RayStatus::Ok);
                EXPECT_EQ(exact.cell, (CellIndex{i, j}));
                EXPECT_EQ(paraxial.cell, (CellIndex{i, j}));
                const double ex = exact.ray.origin.x() - c.x(), px = paraxial.ray.x - c.x();
                const double ey = exact.ray.origin.y() - c.y(), py = paraxial.ray.y - c.y();
                EXPECT_NEAR(exact.ray.origin.z(), system.surfaces[2].z, 1e-12);
                EXPECT_NEAR(ex, px, 1e-9 * std::abs(px));
                EXPECT_NEAR(ey, py, 1e-9 * std::abs(py));
                const Eigen::Vector3d& d = exact.ray.direction;
                EXPECT_NEAR(d.x() / d.z(), paraxial.ray.tx, 1e-9 * std::abs(paraxial.ray.tx));
                EXPECT_NEAR(d.y() / d.z(), paraxial.ray.ty, 1e-9 * std::abs(paraxial.ray.ty));
            }
        }
    }
}

TEST(Exact, SnellAtTheVertexOfADecentredLenslet) {
    // At a lenslet's vertex the normal is the z axis, whatever the lenslet's position:
    // sin(theta') = sin(theta) / n, in the same azimuth.
    const SequentialSystem system = lenslet_array();
    const Lattice& lattice = *system.lattice();
    const double n = system.surfaces[0].index_after;
    std::mt19937_64 random(31);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::uniform_int_distribution<int> column(0, lattice.count_x() - 1), row(0, lattice.count_y() - 1);
    for (int k = 0; k < 2000; ++k) {
        const CellIndex cell{column(random), row(random)};
        const Eigen::Vector2d c = lattice.center(cell);
        const double theta = 0.7 * unit(random), phi = 2 * kPiExact * unit(random);
        const Eigen::Vector3d d = direction_at(theta, phi);
        const TraceResult r = trace(system, ray_through({c.x(), c.y(), 0.0}, d), 0, 0);
        ASSERT_EQ(r.status, RayStatus::Ok);
        EXPECT_EQ(r.cell, cell);
        EXPECT_NEAR((r.ray.origin - Eigen::Vector3d(c.x(), c.y(), 0.0)).norm(), 0.0, 1e-12);
        const Eigen::Vector3d& out = r.ray.direction;
        EXPECT_NEAR(out.head<2>().norm(), std::sin(theta) / n, 1e-12);
        EXPECT_NEAR(out.x() * d.y() - out.y() * d.x(), 0.0, 1e-12);  // same plane of incidence
        EXPECT_GT(out.head<2>().dot(d.head<2>()), -1e-15);
    }
}

TEST(Exact, WrapOverHappensAtTheClosedFormAngle) {
    // The ray through a lenslet's vertex at angle theta and azimuth phi refracts to
    // theta' = asin(sin(theta)/n), crosses the sheet (thickness t), leaves the flat back at
    // theta again, and meets the pattern plane (at z_p) a distance
    //     rho(theta) = t tan(theta') + (z_p - t) tan(theta)
    // from the lenslet's axis. It stays in its cell while rho <= b(phi), the distance to
    // the cell boundary in that direction; the wrap-over angle solves rho = b. The
    // paraxial model has rho = tan(theta) (t/n + z_p - t), so atan(b / (t/n + z_p - t)).
    const SequentialSystem system = lenslet_array();
    const Lattice& lattice = *system.lattice();
    const double n = system.surfaces[0].index_after, t = system.surfaces[1].z, zp = system.surfaces[2].z;
    auto rho = [&](double theta) {
        return t * std::tan(std::asin(std::sin(theta) / n)) + (zp - t) * std::tan(theta);
    };
    std::mt19937_64 random(17);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const CellIndex cell{4, 4};
    const Eigen::Vector2d c = lattice.center(cell);
    for (int k = 0; k < 200; ++k) {
        const double phi = 2 * kPiExact * unit(random);
        const double b = lattice.boundary_distance({std::cos(phi), std::sin(phi)});
        double lo = 0.0, hi = 1.5;
        for (int step = 0; step < 100; ++step) (rho(0.5 * (lo + hi)) < b ? lo : hi) = 0.5 * (lo + hi);
        const double wrap = 0.5 * (lo + hi);
        const double delta = 1e-7;  // moves the landing point by ~4e-7 mm
        const TraceResult inside = trace(system, ray_through({c.x(), c.y(), 0.0}, direction_at(wrap - delta, phi)));
        const TraceResult beyond = trace(system, ray_through({c.x(), c.y(), 0.0}, direction_at(wrap + delta, phi)));
        ASSERT_EQ(inside.status, RayStatus::Ok) << phi;
        EXPECT_EQ(inside.cell, cell);
        const Eigen::Vector2d landing = inside.ray.origin.head<2>() - c;
        EXPECT_NEAR(landing.norm(), rho(wrap - delta), 1e-12);
        EXPECT_NEAR(landing.x() * std::sin(phi) - landing.y() * std::cos(phi), 0.0, 1e-12);
        EXPECT_EQ(beyond.status, RayStatus::CrossedCell) << phi;
        EXPECT_EQ(beyond.surface, 2);
        EXPECT_EQ(beyond.cell, cell);
        // The paraxial model wraps over at its own closed form, earlier than the exact one:
        // tan(asin(sin(theta)/n)) < tan(theta)/n for n > 1, so the exact ray moves less
        // sideways in the glass (the paraxial slope in glass, u/n, overstates it).
        const double wrap_paraxial = std::atan(b / (t / n + zp - t));
        EXPECT_GT(wrap, wrap_paraxial);
        for (const auto& [angle, expected] : {std::pair{wrap_paraxial - delta, RayStatus::Ok},
                                             std::pair{wrap_paraxial + delta, RayStatus::CrossedCell}}) {
            const double slope = std::tan(angle);
            const ParaxialRay start{c.x() - slope * std::cos(phi), c.y() - slope * std::sin(phi),
                                    slope * std::cos(phi), slope * std::sin(phi)};
            EXPECT_EQ(trace_paraxial(system, start, -1.0, 0, 2).status, expected) << phi;
        }
    }
}

TEST(Exact, EntryCellIsTheCellUnderTheHit) {
    // For oblique rays the cell reported is that of the point where the ray met the caps
    // (not of where it crossed the vertex plane), and the point lies on that cell's cap.
    const SequentialSystem system = lenslet_array();
    const Lattice& lattice = *system.lattice();
    std::mt19937_64 random(23);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    const Eigen::Vector2d half = lattice.half_extent();
    int different_from_vertex_plane = 0, checked = 0;
    for (int k = 0; k < 20000; ++k) {
        const double theta = 0.9 * std::abs(unit(random)), phi = kPiExact * unit(random);
        const Eigen::Vector3d d = direction_at(theta, phi);
        const Eigen::Vector3d at(0.9 * half.x() * unit(random), 0.9 * half.y() * unit(random), 0.0);
        const TraceResult r = trace(system, ray_through(at, d), 0, 0);
        if (r.status != RayStatus::Ok) continue;
        ++checked;
        const Eigen::Vector2d p = r.ray.origin.head<2>();
        const CellIndex expected = lattice.cell_at(p);
        if (!(r.cell == expected)) {  // only on a shared edge, where both are nearest
            EXPECT_NEAR((lattice.center(r.cell) - p).norm(), (lattice.center(expected) - p).norm(), 1e-12);
        }
        const Eigen::Vector2d local = p - lattice.center(r.cell);
        EXPECT_NEAR(r.ray.origin.z(), sag(system.surfaces[0].profile, local.squaredNorm()).value(), 1e-12);
        if (!(lattice.cell_at(at.head<2>()) == r.cell)) ++different_from_vertex_plane;
    }
    EXPECT_GT(checked, 19000);
    EXPECT_GT(different_from_vertex_plane, 100);  // the test sees oblique entries
}

TEST(Exact, RaysSkimmingTheArrayAreStoppedAtItsEdge) {
    // Between two rows of caps (distance pitch*sqrt(3)/4 from both rows' centres) the caps
    // are at least sag(1.02 mm) = 0.41 mm deep: a ray 0.3 mm under the vertex plane,
    // almost parallel to it, crosses the whole array without meeting a cap. It is stopped
    // at the array's edge, outside the array, and never "hits" where it started.
    const SequentialSystem system = lenslet_array();
    const Lattice& lattice = *system.lattice();
    const double gap_y = lattice.center({0, 4}).y() + 0.5 * lattice.pitch_y();
    for (double dz : {1e-6, 1e-9, 1e-12, 1e-300}) {
        const Ray ray{{-8.0, gap_y, 0.3}, Eigen::Vector3d(1.0, 0.0, dz).normalized()};
        const TraceResult r = trace(system, ray, 0, 0);
        EXPECT_EQ(r.status, RayStatus::Vignetted) << dz;
        EXPECT_TRUE(r.ray.origin.allFinite());
        EXPECT_GT(r.ray.origin.x(), lattice.half_extent().x()) << dz;
        EXPECT_LT(r.ray.origin.x(), lattice.half_extent().x() + lattice.pitch_x()) << dz;
    }
}

TEST(Exact, GrazingRaysOnTheArrayGiveAStatusAndStayFinite) {
    const SequentialSystem system = lenslet_array();
    const Lattice& lattice = *system.lattice();
    std::mt19937_64 random(29);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    int ok = 0;
    for (int k = 0; k < 3000; ++k) {
        const double below_90 = std::pow(10.0, -1.0 - 8.0 * std::abs(unit(random)));  // 1e-9 .. 0.1 deg
        const double theta = (90.0 - below_90) * kPiExact / 180.0, phi = kPiExact * unit(random);
        const Eigen::Vector3d d = direction_at(theta, phi);
        const Eigen::Vector3d start(15.0 * unit(random), 15.0 * unit(random), -0.01 + 0.5 * std::abs(unit(random)));
        const TraceResult r = trace(system, Ray{start, d});
        EXPECT_TRUE(r.ray.origin.allFinite()) << theta;
        EXPECT_TRUE(r.ray.direction.allFinite());
        EXPECT_NEAR(r.ray.direction.norm(), 1.0, 1e-12);
        if (r.surface == 0 && r.status == RayStatus::Vignetted) {
            // Stopped at a point outside the array (where it entered the slab of caps, or
            // where it left the array's box without meeting a cap).
            EXPECT_FALSE(lattice.contains(lattice.cell_at(r.ray.origin.head<2>())));
        }
        if (r.has_cell) {
            // Entered a lenslet: the entry point was on its cap (checked on surface 0 alone).
            const TraceResult entry = trace(system, Ray{start, d}, 0, 0);
            ASSERT_EQ(entry.status, RayStatus::Ok);
            const Eigen::Vector2d local = entry.ray.origin.head<2>() - lattice.center(entry.cell);
            EXPECT_TRUE(lattice.cell_contains(entry.cell, entry.ray.origin.head<2>()));
            EXPECT_NEAR(entry.ray.origin.z(), sag(system.surfaces[0].profile, local.squaredNorm()).value(), 1e-9);
            ++ok;
        }
    }
    EXPECT_GT(ok, 0);
}

TEST(Exact, SteepRaysOnAPlanoConvexLensFailForTheRightReason) {
    // 85 to 89.9 degrees across the aperture, both ways round. Every outcome is a status
    // with finite numbers, and each total internal reflection or vignetting is the one
    // the closed forms predict from where the ray met the surface:
    //  - at a flat exit, TIR iff the sine of the angle in the glass exceeds 1/n;
    //  - at the curved exit (c = -1/R), the normal at height y is tilted by asin(y/R), so in
    //    the y-z plane TIR iff |theta_glass - asin(y/R)| > asin(1/n);
    //  - vignetting iff the hit lies beyond the semi-diameter.
    const double n = 1.5168, critical = std::asin(1 / n), radius = 25.8;
    std::array<int, kRayStatusCount> seen{};
    for (bool curved_first : {true, false}) {
        const SequentialSystem system = pcx(curved_first);
        for (double degrees = 85.0; degrees <= 89.9 + 1e-9; degrees += 0.1) {
            const Eigen::Vector3d d = direction_at(degrees * kPiExact / 180.0, kPiExact / 2);
            for (double h = -12.0; h <= 12.0; h += 0.5) {
                const Ray ray = ray_through({0.0, h, 0.0}, d);
                const TraceResult r = trace(system, ray);
                ASSERT_TRUE(r.ray.origin.allFinite() && r.ray.direction.allFinite()) << degrees << " " << h;
                ++seen[static_cast<std::size_t>(r.status)];
                if (r.status == RayStatus::Missed || r.status == RayStatus::Ok) continue;
                ASSERT_NE(r.status, RayStatus::CrossedCell);
                const std::size_t s = static_cast<std::size_t>(r.surface);
                const double rim = r.ray.origin.head<2>().norm();
                if (r.status == RayStatus::Vignetted) {
                    EXPECT_GT(rim, 12.5) << degrees << " " << h;
                    continue;
                }
                // TIR: at the exit surface, with the ray as it was inside the glass.
                ASSERT_EQ(s, 1u);
                EXPECT_LE(rim, 12.5 * (1 + kApertureTolerance));
                const Eigen::Vector3d inside = trace(system, ray, 0, 0).ray.direction;
                if (curved_first) {
                    EXPECT_GT(inside.head<2>().norm(), 1 / n);
                } else {
                    const double theta_glass = std::atan2(inside.y(), inside.z());
                    EXPECT_GT(std::abs(theta_glass - std::asin(r.ray.origin.y() / radius)), critical);
                }
            }
        }
    }
    // Conversely: rays that got through had angles below the critical one at the exit.
    for (bool curved_first : {true, false}) {
        const SequentialSystem system = pcx(curved_first);
        for (double degrees = 85.0; degrees <= 89.9 + 1e-9; degrees += 0.1) {
            const Eigen::Vector3d d = direction_at(degrees * kPiExact / 180.0, kPiExact / 2);
            for (double h = -12.0; h <= 12.0; h += 0.5) {
                const Ray ray = ray_through({0.0, h, 0.0}, d);
                const TraceResult exit = trace(system, ray, 0, 1);
                if (exit.status != RayStatus::Ok) continue;
                const Eigen::Vector3d inside = trace(system, ray, 0, 0).ray.direction;
                if (curved_first) {
                    EXPECT_LE(inside.head<2>().norm(), 1 / n);
                } else {
                    const double theta_glass = std::atan2(inside.y(), inside.z());
                    EXPECT_LE(std::abs(theta_glass - std::asin(exit.ray.origin.y() / radius)), critical + 1e-12);
                }
            }
        }
    }
    EXPECT_GT(seen[static_cast<std::size_t>(RayStatus::TotalInternalReflection)], 0);
    EXPECT_GT(seen[static_cast<std::size_t>(RayStatus::Vignetted)], 0);
    EXPECT_GT(seen[static_cast<std::size_t>(RayStatus::Missed)], 0);
}

TEST(Exact, RaysParallelToOrAwayFromTheSurfacesMissThem) {
    const SequentialSystem system = pcx(false);  // flat first
    EXPECT_EQ(trace(system, Ray{{0, 0, -1}, {0, 1, 0}}).status, RayStatus::Missed);
    EXPECT_EQ(trace(system, Ray{{0, 0, -1}, {0, 0, -1}}).status, RayStatus::Missed);
    const TraceResult back = trace(system, Ray{{0, 0, -1}, Eigen::Vector3d(0, 0.3, -1).normalized()});
    EXPECT_EQ(back.status, RayStatus::Missed);
    EXPECT_EQ(back.surface, 0);
    EXPECT_TRUE(back.ray.origin.allFinite());
    EXPECT_EQ(trace(lenslet_array(), Ray{{0, 0, -1}, {1, 0, 0}}).status, RayStatus::Missed);
}

TEST(Exact, ReversingThroughALensletArrayReturnsToTheStart) {
    // In the reversed frame the caps are concave toward the light (c < 0): the same cell
    // must be found from the other side and the ray must come back along its own line.
    const SequentialSystem system = lenslet_array();
    const SequentialSystem back = reversed(system);
    const Lattice& lattice = *system.lattice();
    std::mt19937_64 random(37);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    int checked = 0;
    for (int k = 0; k < 3000; ++k) {
        const CellIndex cell{static_cast<int>(4 + 4 * unit(random)), static_cast<int>(4 + 4 * unit(random))};
        const Eigen::Vector2d c = lattice.center(cell);
        const Eigen::Vector3d start(c.x() + 0.6 * unit(random), c.y() + 0.6 * unit(random), -1.0);
        const Eigen::Vector3d d = Eigen::Vector3d(0.15 * unit(random), 0.15 * unit(random), 1.0).normalized();
        const TraceResult forward = trace(system, Ray{start, d});
        if (forward.status != RayStatus::Ok) continue;
        const Eigen::Vector3d o(forward.ray.origin.x(), forward.ray.origin.y(), -forward.ray.origin.z());
        const Eigen::Vector3d r(-forward.ray.direction.x(), -forward.ray.direction.y(), forward.ray.direction.z());
        const TraceResult home = trace(back, Ray{o - 1e-3 * r, r});
        ASSERT_EQ(home.status, RayStatus::Ok);
        EXPECT_EQ(home.cell, forward.cell);
        const Eigen::Vector3d p(home.ray.origin.x(), home.ray.origin.y(), -home.ray.origin.z());
        const Eigen::Vector3d dir(-home.ray.direction.x(), -home.ray.direction.y(), home.ray.direction.z());
        EXPECT_NEAR((p - start).cross(d).norm(), 0.0, 1e-9);
        EXPECT_NEAR((dir - d).norm(), 0.0, 1e-12);
        ++checked;
    }
    EXPECT_GT(checked, 2000);
}

TEST(Exact, RaysLeavingAnySurfaceNeverMeetItAtTheirStart) {
    // Spheres both ways, paraboloid, hyperboloid, prolate and oblate ellipsoids, a flat:
    // a ray refracted at a point of the surface, leaving on either side, gets no hit at
    // t ~ 0 from intersect(t_min = 0); a later hit, if any, is a real one on the surface.
    std::mt19937_64 random(41);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (const Profile& profile :
         {Profile(Conic{1 / 5.0}), Profile(Conic{-1 / 5.0}), Profile(Conic{1 / 4.0, -1.0}),
          Profile(Conic{-1 / 4.0, -2.5}), Profile(Conic{1 / 6.0, -0.5}), Profile(Conic{1 / 6.0, 0.8}),
          Profile(Flat{})}) {
        int checked = 0;
        for (int k = 0; k < 4000; ++k) {
            const double x = 2.0 * unit(random), y = 2.0 * unit(random);
            const auto z = sag(profile, x * x + y * y);
            if (!z) continue;
            const Eigen::Vector3d on(x, y, *z);
            const double side = k % 2 == 0 ? 1.0 : -1.0;  // toward +z (into glass) or -z (out)
            const Eigen::Vector3d in =
                Eigen::Vector3d(0.4 * unit(random), 0.4 * unit(random), side).normalized();
            const auto out = refract(in, normal_at(profile, on), side > 0 ? 1.0 / 1.5 : 1.5);
            if (!out) continue;  // total internal reflection on the way out
            ++checked;
            const auto again = intersect(profile, on, *out, 0.0);
            if (again) {
                EXPECT_GT(*again, 1e-6);
                const Eigen::Vector3d p = on + *again * *out;
                EXPECT_NEAR(p.z(), sag(profile, p.head<2>().squaredNorm()).value(), 1e-9);
            }
        }
        EXPECT_GT(checked, 2500);
    }
}

}  // namespace
}  // namespace rfd::optics

namespace rfd::optics {
namespace {

// Two equal biconvex lenses whose vertices touch at z = 4 (faces R = +-20 mm, n = 1.5168),
// and the same glass fused into one 8 mm lens. At the contact point both faces have the
// normal +z, so a ray through it refracts out of the first lens and back into the second at
// one point, unchanged: through the contact the pair traces like the fused lens.
SequentialSystem touching_biconvex_pair() {
    SequentialSystem s;
    s.surfaces.push_back({Conic{1 / 20.0}, CircularAperture{5.0}, 0.0, 1.5168, "A front"});
    s.surfaces.push_back({Conic{-1 / 20.0}, CircularAperture{5.0}, 4.0, 1.0, "A back"});
    s.surfaces.push_back({Conic{1 / 20.0}, CircularAperture{5.0}, 4.0, 1.5168, "B front"});
    s.surfaces.push_back({Conic{-1 / 20.0}, CircularAperture{5.0}, 8.0, 1.0, "B back"});
    return with_image_plane(s, 30.0);
}

SequentialSystem fused_biconvex() {
    SequentialSystem s;
    s.surfaces.push_back({Conic{1 / 20.0}, CircularAperture{5.0}, 0.0, 1.5168, "front"});
    s.surfaces.push_back({Conic{-1 / 20.0}, CircularAperture{5.0}, 8.0, 1.0, "back"});
    return with_image_plane(s, 30.0);
}

// The ray in front of the first face (R = 20 mm, vertex at z = 0, index n behind it) that
// runs inside the glass through `target` along `inside`: sphere intersection and Snell's
// law worked backwards, by hand.
Ray ray_reaching(const Eigen::Vector3d& target, const Eigen::Vector3d& inside, double n) {
    const Eigen::Vector3d centre(0.0, 0.0, 20.0);
    // |w - s inside|^2 = 20^2 with w = target - centre: s = b +- sqrt(b^2 - c); the vertex
    // cap is the nearer crossing behind the target, the smaller positive root.
    const Eigen::Vector3d w = target - centre;
    const double b = w.dot(inside), c = w.squaredNorm() - 400.0;
    const double s = b + std::sqrt(b * b - c);
    const Eigen::Vector3d entry = target - s * inside;
    const Eigen::Vector3d normal = (centre - entry).normalized();  // toward +z at the vertex
    // Snell: n (inside x normal) = (outside x normal), outside on the same side of the normal.
    const Eigen::Vector3d tangential = n * (inside - inside.dot(normal) * normal);
    const Eigen::Vector3d outside =
        tangential + std::sqrt(1.0 - tangential.squaredNorm()) * normal;
    return Ray{entry - 1.0 * outside, outside};
}

TEST(Exact, ARayThroughTheContactOfTwoCurvedFacesPassesIt) {
    const SequentialSystem pair = touching_biconvex_pair();
    const SequentialSystem fused = fused_biconvex();
    const double image_z = pair.surfaces.back().z;
    // On the axis: through both vertices, straight on to the image plane's centre.
    const TraceResult axial = trace(pair, Ray{{0.0, 0.0, -1.0}, Eigen::Vector3d::UnitZ()});
    ASSERT_EQ(axial.status, RayStatus::Ok) << "stopped at " << axial.surface;
    EXPECT_EQ(axial.surface, 4);
    EXPECT_NEAR((axial.ray.origin - Eigen::Vector3d(0.0, 0.0, image_z)).norm(), 0.0, 1e-12);
    EXPECT_NEAR((axial.ray.direction - Eigen::Vector3d::UnitZ()).norm(), 0.0, 1e-15);
    // Oblique rays through the contact point, which rounding puts a few 1e-16 mm off it.
    for (double degrees : {0.5, 3.0, 10.0, 20.0}) {
        for (double azimuth : {0.0, 1.0, 2.5}) {
            const double a = degrees * std::numbers::pi / 180.0;
            const Eigen::Vector3d inside(std::sin(a) * std::cos(azimuth), std::sin(a) * std::sin(azimuth),
                                         std::cos(a));
            const Ray ray = ray_reaching({0.0, 0.0, 4.0}, inside, 1.5168);
            const TraceResult through_pair = trace(pair, ray);
            const TraceResult through_fused = trace(fused, ray);
            ASSERT_EQ(through_fused.status, RayStatus::Ok);
            ASSERT_EQ(through_pair.status, RayStatus::Ok)
                << degrees << " deg: stopped at " << pair.surfaces[static_cast<std::size_t>(through_pair.surface)].label;
            EXPECT_NEAR((through_pair.ray.origin - through_fused.ray.origin).norm(), 0.0, 1e-12) << degrees;
            EXPECT_NEAR((through_pair.ray.direction - through_fused.ray.direction).norm(), 0.0, 1e-14) << degrees;
        }
    }
}

// The other half of the contact rule: a ray on a surface that it has not crossed yet
// (t_min < 0) meets it right there when it goes from the front to the back (along the
// normal, which points to +z at the vertex), and never when it goes the other way.
TEST(Exact, ARayOnASurfaceNotYetCrossedMeetsItThereOnlyGoingFrontToBack) {
    std::mt19937_64 random(43);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (const Profile& profile :
         {Profile(Conic{1 / 5.0}), Profile(Conic{-1 / 5.0}), Profile(Conic{1 / 4.0, -1.0}),
          Profile(Conic{-1 / 4.0, -2.5}), Profile(Conic{1 / 6.0, 0.8})}) {
        int forward = 0, backward = 0;
        for (int k = 0; k < 4000; ++k) {
            const double x = 2.0 * unit(random), y = 2.0 * unit(random);
            const auto z = sag(profile, x * x + y * y);
            if (!z) continue;
            const Eigen::Vector3d on(x, y, *z);
            const Eigen::Vector3d d = Eigen::Vector3d(unit(random), unit(random), unit(random)).normalized();
            const double across = normal_at(profile, on).dot(d);
            if (std::abs(across) < 1e-3) continue;  // grazing: either answer is rounding
            const auto t = intersect(profile, on, d, -1e-9);
            if (across > 0) {
                ++forward;
                ASSERT_TRUE(t.has_value());
                EXPECT_LE(std::abs(*t), 1e-9);
            } else {
                ++backward;
                if (t) {
                    EXPECT_GT(*t, 1e-6);
                }
            }
        }
        EXPECT_GT(forward, 1000);
        EXPECT_GT(backward, 1000);
    }
}

// A biconcave lens of zero centre thickness (R = -+20 mm): its faces touch at the vertex,
// where both normals are +z, so the chief ray through the vertex leaves it undeviated.
TEST(Exact, AZeroThicknessBiconcaveLensPassesTheChiefRayUndeviated) {
    SequentialSystem s;
    s.surfaces.push_back({Conic{-1 / 20.0}, CircularAperture{5.0}, 0.0, 1.5168, "front"});
    s.surfaces.push_back({Conic{1 / 20.0}, CircularAperture{5.0}, 0.0, 1.0, "back"});
    s = with_image_plane(s, 25.0);
    for (double degrees : {0.0, 2.0, 5.0, 30.0}) {
        const double a = degrees * std::numbers::pi / 180.0;
        const Eigen::Vector3d d(0.0, std::sin(a), std::cos(a));
        const TraceResult result = trace(s, Ray{-1.0 / d.z() * d, d});
        ASSERT_EQ(result.status, RayStatus::Ok) << degrees << " deg: stopped at " << result.surface;
        EXPECT_NEAR(result.ray.origin.y(), 25.0 * std::tan(a), 1e-12) << degrees;
        EXPECT_NEAR((result.ray.direction - d).norm(), 0.0, 1e-15) << degrees;
    }
}

}  // namespace
}  // namespace rfd::optics
