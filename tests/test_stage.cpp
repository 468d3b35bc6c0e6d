// The virtual light stage against closed forms and independent computations: Lambertian
// shading, cast shadows, mirror highlights, Snell refraction, Beer-Lambert absorption,
// penumbrae of wide kernels, kernel normalisation, BRDF energy bounds, determinism, scene
// errors, and OBJ/PLY equivalence.

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <optional>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "core/error.hpp"
#include "core/image_io.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/brdf.hpp"
#include "relight/light_kernel.hpp"
#include "relight/mesh.hpp"
#include "relight/ray_scene.hpp"
#include "relight/scene.hpp"
#include "relight/stage.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/temp_dir.hpp"

namespace rfd::relight {
namespace {

using ::testing::HasSubstr;
using ::testing::MatchesRegex;
using rfd::testing::TempDir;

using rfd::testing::error_of;

// ---- independent geometry, written apart from the renderer ----

// The pinhole model of the scene format: ray through image point (px, py).
Eigen::Vector3d pinhole_ray(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                            const Eigen::Vector3d& up, double fov_deg, int w, int h, double px,
                            double py) {
    const Eigen::Vector3d f = (target - eye).normalized();
    const Eigen::Vector3d r = f.cross(up).normalized();
    const Eigen::Vector3d u = r.cross(f);
    const double t = std::tan(degrees_to_radians(fov_deg) / 2);
    const double sx = (2 * px / w - 1) * t * w / h;
    const double sy = (1 - 2 * py / h) * t;
    return (f + sx * r + sy * u).normalized();
}

// Pixel coordinates of a world point under the same camera.
Eigen::Vector2d project(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                        const Eigen::Vector3d& up, double fov_deg, int w, int h,
                        const Eigen::Vector3d& p) {
    const Eigen::Vector3d f = (target - eye).normalized();
    const Eigen::Vector3d r = f.cross(up).normalized();
    const Eigen::Vector3d u = r.cross(f);
    const Eigen::Vector3d q = p - eye;
    const double t = std::tan(degrees_to_radians(fov_deg) / 2);
    const double sx = q.dot(r) / q.dot(f), sy = q.dot(u) / q.dot(f);
    return {(sx / (t * w / h) + 1) * w / 2, (1 - sy / t) * h / 2};
}

std::optional<double> ray_sphere(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                 const Eigen::Vector3d& c, double r) {
    const double b = (o - c).dot(d);
    const double disc = b * b - ((o - c).squaredNorm() - r * r);
    if (disc < 0) return std::nullopt;
    const double t0 = -b - std::sqrt(disc), t1 = -b + std::sqrt(disc);
    if (t0 > 1e-9) return t0;
    if (t1 > 1e-9) return t1;
    return std::nullopt;
}

Eigen::Vector3d snell(const Eigen::Vector3d& d, Eigen::Vector3d n, double n1, double n2) {
    if (d.dot(n) > 0) n = -n;  // n against the ray
    const double ci = -d.dot(n), eta = n1 / n2;
    const double ct = std::sqrt(1 - eta * eta * (1 - ci * ci));
    return (eta * d + (eta * ci - ct) * n).normalized();
}

std::string camera_toml(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, double fov_deg,
                        int w, int h, int spp) {
    char text[512];
    std::snprintf(text, sizeof text,
                  "[[camera]]\nposition_mm = [%.17g, %.17g, %.17g]\nlook_at_mm = [%.17g, %.17g, %.17g]\n"
                  "up = [0, 1, 0]\nfov_deg = %.17g\nresolution = [%d, %d]\nsamples_per_pixel = %d\n",
                  eye.x(), eye.y(), eye.z(), target.x(), target.y(), target.z(), fov_deg, w, h, spp);
    return text;
}

Scene scene_from(const std::string& text, const std::filesystem::path& dir = ".") {
    return parse_scene(text, "test.toml", dir);
}

// ---- light kernels ----

// 2 pi * integral K(a) sin(a) da by a fine midpoint rule, with the profile written out here.
double profile(const LightKernel& k, double a) {
    if (a > k.radius) return 0;
    switch (k.profile) {
        case KernelProfile::Constant: return 1;
        case KernelProfile::Smooth: return std::pow(std::cos(kPi * a / (2 * k.radius)), 2);
        case KernelProfile::Gaussian: return std::exp(-a * a / (2 * k.sigma * k.sigma));
    }
    return 0;
}

TEST(LightKernel, IntegratesToOneOverTheSphere) {
    for (const LightKernel& kernel : {LightKernel::narrow(), LightKernel::wide(),
                                      LightKernel::gaussian(degrees_to_radians(4.0)),
                                      LightKernel{KernelProfile::Constant, degrees_to_radians(40.0), 0}}) {
        const KernelSampler sampler(kernel);
        // A lat-long grid around a tilted centre: checks radiance(w, d) as a function on
        // the sphere, not only the radial profile.
        const Eigen::Vector3d d = direction_from_angles(degrees_to_radians(50), degrees_to_radians(20));
        const int n_theta = 1200, n_phi = 2400;
        double total = 0;
        for (int i = 0; i < n_theta; ++i) {
            const double theta = (i + 0.5) * kPi / n_theta;
            for (int j = 0; j < n_phi; ++j) {
                const double phi = (j + 0.5) * 2 * kPi / n_phi;
                total += sampler.radiance(direction_from_angles(theta, phi), d) * std::sin(theta);
            }
        }
        total *= (kPi / n_theta) * (2 * kPi / n_phi);
        EXPECT_NEAR(total, 1.0, 0.01) << to_string(kernel.profile) << " " << kernel.radius;
        // The radial integral at 100x finer resolution.
        const int steps = 200000;
        double radial = 0;
        for (int i = 0; i < steps; ++i) {
            const double a = (i + 0.5) * kernel.radius / steps;
            radial += sampler.radiance(a) * std::sin(a);
        }
        radial *= 2 * kPi * kernel.radius / steps;
        EXPECT_NEAR(radial, 1.0, 1e-6);
        // Against the profile written out here: the normalisation constant is the same.
        EXPECT_NEAR(sampler.radiance(0.3 * kernel.radius) / sampler.radiance(0.0),
                    profile(kernel, 0.3 * kernel.radius), 1e-12);
    }
}

TEST(LightKernel, SamplesFollowTheKernel) {
    // Mean cosine to the centre of K-distributed samples against the closed form of the
    // constant cap, (1 + cos r) / 2, and a quadrature of the smooth profile.
    for (const LightKernel& kernel : {LightKernel{KernelProfile::Constant, degrees_to_radians(20.0), 0},
                                      LightKernel::wide()}) {
        const KernelSampler sampler(kernel);
        const Eigen::Vector3d d = Eigen::Vector3d(0.2, -0.3, 0.9).normalized();
        const int n = 256;
        double mean_cos = 0;
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                const Eigen::Vector3d w = sampler.sample(d, (i + 0.5) / n, (j + 0.5) / n);
                EXPECT_LE(angle_between(w, d), kernel.radius + 1e-9);
                mean_cos += w.dot(d);
                mean += w;
            }
        mean_cos /= n * n;
        double expected = (1 + std::cos(kernel.radius)) / 2;
        if (kernel.profile != KernelProfile::Constant) {
            double num = 0, den = 0;
            for (int i = 0; i < 100000; ++i) {
                const double a = (i + 0.5) * kernel.radius / 100000;
                num += profile(kernel, a) * std::sin(a) * std::cos(a);
                den += profile(kernel, a) * std::sin(a);
            }
            expected = num / den;
        }
        EXPECT_NEAR(mean_cos, expected, 2e-5);
        EXPECT_LT(angle_between(mean.normalized(), d), 1e-6);  // symmetric about the centre
    }
    // The smooth profile reaches half its maximum at half its radius.
    const KernelSampler wide(LightKernel::wide());
    EXPECT_NEAR(wide.radiance(wide.kernel().radius / 2) / wide.radiance(0.0), 0.5, 1e-12);
    EXPECT_DOUBLE_EQ(wide.quantile_angle(1.0), wide.kernel().radius);
    EXPECT_DOUBLE_EQ(wide.quantile_angle(0.0), 0.0);
}

// ---- reflection models ----

// Integral of f(l) cos over the hemisphere around +z, midpoint rule.
double directional_albedo(const std::function<Rgb(const Eigen::Vector3d&)>& f) {
    const int n_theta = 400, n_phi = 800;
    double total = 0;
    for (int i = 0; i < n_theta; ++i) {
        const double theta = (i + 0.5) * (kPi / 2) / n_theta;
        for (int j = 0; j < n_phi; ++j) {
            const Eigen::Vector3d l = direction_from_angles(theta, (j + 0.5) * 2 * kPi / n_phi);
            total += f(l)[0] * std::cos(theta) * std::sin(theta);
        }
    }
    return total * (kPi / 2 / n_theta) * (2 * kPi / n_phi);
}

TEST(Brdf, GlossyNeverReflectsMoreThanItReceives) {
    const Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
    double largest = 0;
    for (const double specular : {0.04, 0.5, 1.0})
        for (const double alpha : {0.05, 0.3, 1.0})
            for (const double view_deg : {0.0, 45.0, 80.0, 89.0}) {
                const Eigen::Vector3d v = direction_from_angles(degrees_to_radians(view_deg), 0.3);
                const double albedo = directional_albedo([&](const Eigen::Vector3d& l) {
                    return glossy_brdf(n, v, l, Rgb::Ones(), Rgb::Constant(specular), alpha);
                });
                EXPECT_LE(albedo, 1.0 + 5e-3) << specular << " " << alpha << " " << view_deg;
                largest = std::max(largest, albedo);
            }
    EXPECT_GT(largest, 0.8);  // and it is not trivially dark
    // Lambert: albedo exactly (quadrature error only).
    const double lambert = directional_albedo([&](const Eigen::Vector3d& l) {
        return lambert_brdf(n, l, Rgb::Constant(0.7));
    });
    EXPECT_NEAR(lambert, 0.7, 1e-4);
}

TEST(Brdf, GlossyIsReciprocal) {
    const Eigen::Vector3d n = Eigen::Vector3d(0.1, -0.2, 1.0).normalized();
    for (int i = 0; i < 50; ++i) {
        const Eigen::Vector3d v = direction_from_angles(0.03 * i, 0.7 * i);
        const Eigen::Vector3d l = direction_from_angles(0.025 * (50 - i), -0.4 * i);
        const Rgb a = glossy_brdf(n, v, l, Rgb(0.5, 0.2, 0.1), Rgb::Constant(0.05), 0.2);
        const Rgb b = glossy_brdf(n, l, v, Rgb(0.5, 0.2, 0.1), Rgb::Constant(0.05), 0.2);
        EXPECT_NEAR((a - b).abs().maxCoeff(), 0.0, 1e-9 * (1 + a.maxCoeff()));
    }
}

TEST(Brdf, FresnelKnownAngles) {
    EXPECT_NEAR(fresnel_dielectric(1.0, 1.0, 1.5), 0.04, 1e-12);
    // Brewster's angle: p-polarised reflectance vanishes, leaving half of rs^2.
    const double brewster = std::atan(1.5);
    const double ci = std::cos(brewster), ct = std::cos(kPi / 2 - brewster);
    const double rs = (ci - 1.5 * ct) / (ci + 1.5 * ct);
    EXPECT_NEAR(fresnel_dielectric(ci, 1.0, 1.5), 0.5 * rs * rs, 1e-12);
    // Total internal reflection past the critical angle, from glass to air.
    const double critical = std::asin(1 / 1.5);
    EXPECT_EQ(fresnel_dielectric(std::cos(critical + 0.01), 1.5, 1.0), 1.0);
    EXPECT_LT(fresnel_dielectric(std::cos(critical - 0.01), 1.5, 1.0), 1.0);
}

// ---- rendering against closed forms ----

TEST(Stage, LambertianSphereMatchesClosedForm) {
    const Eigen::Vector3d eye(0, 0, 1000), target(0, 0, 0), centre(3, -2, 0);
    const double radius = 30, albedo = 0.7, fov = 4;
    const int w = 64, h = 64;
    const Scene scene = scene_from(camera_toml(eye, target, fov, w, h, 1) + R"(
[kernel]
profile = "directional"
[materials.white]
type = "diffuse"
albedo = [0.7, 0.7, 0.7]
[[object]]
type = "sphere"
material = "white"
center_mm = [3, -2, 0]
radius_mm = 30
)");
    const LightStage stage(scene);
    int sphere_pixels = 0;
    for (const Eigen::Vector3d& light :
         {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0.5, 0.3, 0.8).normalized(),
          Eigen::Vector3d(-0.9, 0.1, 0.2).normalized()}) {
        const Image image = stage.render(light);
        sphere_pixels = 0;
        double worst = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const Eigen::Vector3d d = pinhole_ray(eye, target, Eigen::Vector3d::UnitY(), fov, w, h, x + 0.5, y + 0.5);
                const auto t = ray_sphere(eye, d, centre, radius);
                double expected = 0;
                if (t) {
                    ++sphere_pixels;
                    const Eigen::Vector3d n = (eye + *t * d - centre).normalized();
                    expected = albedo / kPi * std::max(0.0, n.dot(light));
                }
                for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(image.at(x, y, c) - expected));
            }
        EXPECT_LT(worst, 2e-6) << light.transpose();
    }
    EXPECT_GT(sphere_pixels, 1500);
}

TEST(Stage, ConstantKernelAveragesTheCosineOverItsCap) {
    // Away from the terminator, a constant cap of radius r gives (1/pi) n.d (1 + cos r) / 2:
    // the mean of w over the cap is d times the mean cosine. A 20-degree cap makes that
    // factor 0.970, far outside the tolerance, so a renderer treating the kernel as a
    // directional light fails. One camera ray per pixel (the centre, where the normal is
    // computed here) and 64 kernel samples per pixel.
    const Eigen::Vector3d eye(0, 0, 1000), target(0, 0, 0);
    const double fov = 4, r = degrees_to_radians(20.0);
    const int w = 48, h = 48;
    const Scene scene = scene_from(camera_toml(eye, target, fov, w, h, 1) + R"(
[kernel]
profile = "constant"
radius_deg = 20
shadow_samples = 64
[materials.white]
type = "diffuse"
albedo = [1, 1, 1]
[[object]]
type = "sphere"
material = "white"
center_mm = [0, 0, 0]
radius_mm = 30
)");
    const LightStage stage(scene);
    const Eigen::Vector3d light = Eigen::Vector3d(0.3, 0.2, 0.9).normalized();
    const Image image = stage.render(light);
    double sum_error = 0, sum_expected = 0, sum_directional_error = 0;
    int count = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const Eigen::Vector3d d = pinhole_ray(eye, target, Eigen::Vector3d::UnitY(), fov, w, h, x + 0.5, y + 0.5);
            const auto t = ray_sphere(eye, d, Eigen::Vector3d::Zero(), 30);
            if (!t) continue;
            const Eigen::Vector3d n = (eye + *t * d).normalized();
            // The whole cap above the horizon: angle(n, light) + r < 90 degrees.
            if (n.dot(light) < 0.5) continue;
            const double expected = 1 / kPi * n.dot(light) * (1 + std::cos(r)) / 2;
            sum_error += image.at(x, y, 0) - expected;
            sum_directional_error += image.at(x, y, 0) - 1 / kPi * n.dot(light);
            sum_expected += expected;
            ++count;
        }
    ASSERT_GT(count, 500);
    // Per pixel the rotated kernel lattice leaves some noise; the mean over pixels cancels it.
    EXPECT_LT(std::abs(sum_error) / sum_expected, 2e-3);
    EXPECT_GT(std::abs(sum_directional_error) / sum_expected, 0.02);
}

TEST(Stage, SphereShadowFallsWhereGeometryPutsIt) {
    const Eigen::Vector3d eye(0, 0, 1500), target(0, 0, 0), centre(-10, 5, 40);
    const double fov = 8, radius = 20;
    const int w = 96, h = 96;
    const Scene scene = scene_from(camera_toml(eye, target, fov, w, h, 1) + R"(
[kernel]
profile = "directional"
[materials.grey]
type = "diffuse"
albedo = [0.5, 0.5, 0.5]
[[object]]
type = "card"
material = "grey"
center_mm = [0, 0, 0]
size_mm = [400, 400]
[[object]]
type = "sphere"
material = "grey"
center_mm = [-10, 5, 40]
radius_mm = 20
)");
    const LightStage stage(scene);
    const Eigen::Vector3d light = Eigen::Vector3d(0.6, -0.3, 0.75).normalized();
    const Image image = stage.render(light);
    int shadow = 0, mismatches = 0, naive_mismatches = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const Eigen::Vector3d d = pinhole_ray(eye, target, Eigen::Vector3d::UnitY(), fov, w, h, x + 0.5, y + 0.5);
            if (ray_sphere(eye, d, centre, radius)) continue;  // sees the sphere itself
            const Eigen::Vector3d p = eye + (-eye.z() / d.z()) * d;  // on the card, z = 0
            const bool shadowed = ray_sphere(p, light, centre, radius).has_value();
            // A wrong shadow model for contrast: the sphere's footprint straight below it.
            const bool below = (p.head<2>() - centre.head<2>()).norm() < radius;
            const double lit = 0.5 / kPi * light.z();
            shadow += shadowed;
            const bool rendered_dark = image.at(x, y, 1) < 0.5 * lit;
            mismatches += rendered_dark != shadowed;
            naive_mismatches += rendered_dark != below;
            if (!shadowed) {
                EXPECT_NEAR(image.at(x, y, 1), lit, 1e-6);
            }
        }
    EXPECT_GT(shadow, 150);
    EXPECT_LE(mismatches, 2);
    EXPECT_GT(naive_mismatches, 100);
}

TEST(Stage, MirrorSphereShowsTheKernelAtTheReflectionPoint) {
    const Eigen::Vector3d eye(0, 0, 1000), target(0, 0, 0);
    const double fov = 4, radius = 30, cap = degrees_to_radians(8.0);
    const int w = 96, h = 96;
    const Scene scene = scene_from(camera_toml(eye, target, fov, w, h, 4) + R"(
[kernel]
profile = "constant"
radius_deg = 8
[materials.chrome]
type = "mirror"
reflectance = [1, 1, 1]
[[object]]
type = "sphere"
material = "chrome"
center_mm = [0, 0, 0]
radius_mm = 30
)");
    const LightStage stage(scene);
    const Eigen::Vector3d light = Eigen::Vector3d(0.3, 0.2, 1).normalized();
    const Image image = stage.render(light);
    // Where the mirror reflects the eye into the light: the normal halves view and light.
    Eigen::Vector3d p = radius * light;
    for (int i = 0; i < 50; ++i) p = radius * ((eye - p).normalized() + light).normalized();
    const Eigen::Vector2d expected = project(eye, target, Eigen::Vector3d::UnitY(), fov, w, h, p);
    double sum = 0, sx = 0, sy = 0, peak = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const double v = image.at(x, y, 0);
            sum += v;
            sx += v * (x + 0.5);
            sy += v * (y + 0.5);
            peak = std::max(peak, v);
        }
    ASSERT_GT(sum, 0);
    EXPECT_NEAR(sx / sum, expected.x(), 0.3);
    EXPECT_NEAR(sy / sum, expected.y(), 0.3);
    // Inside the reflected disc the mirror shows the kernel's radiance, 1 / solid angle.
    EXPECT_NEAR(peak, 1 / (2 * kPi * (1 - std::cos(cap))), 1e-3 * peak);
}

TEST(Stage, NearLampLightsEachPointFromItsOwnDirection) {
    // A near lamp 150 mm above a Lambertian sphere: each point sees it from its own
    // direction, at its own distance (irradiance (d0 / d)^2); a mirror sphere beside it
    // shows the lamp where the mirror law for the lamp's position puts it.
    const Eigen::Vector3d eye(0, 0, 1000), target(0, 0, 0), white(-20, 0, 0), chrome(20, 0, 0);
    const double fov = 4, radius = 15, albedo = 0.7;
    const int w = 96, h = 96;
    const Scene scene = scene_from(camera_toml(eye, target, fov, w, h, 1) + R"(
[kernel]
profile = "directional"
[materials.white]
type = "diffuse"
albedo = [0.7, 0.7, 0.7]
[materials.chrome]
type = "mirror"
reflectance = [1, 1, 1]
[[object]]
type = "sphere"
material = "white"
center_mm = [-20, 0, 0]
radius_mm = 15
[[object]]
type = "sphere"
material = "chrome"
center_mm = [20, 0, 0]
radius_mm = 15
)");
    const LightStage stage(scene);
    const NearLamp lamp{Eigen::Vector3d(40, 60, 150), 15.0, 100.0};
    const Image image = stage.render(lamp);
    double worst = 0, sum = 0, sx = 0, sy = 0, peak = 0;
    int lit = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const Eigen::Vector3d d = pinhole_ray(eye, target, Eigen::Vector3d::UnitY(), fov, w, h, x + 0.5, y + 0.5);
            if (const auto t = ray_sphere(eye, d, white, radius)) {
                const Eigen::Vector3d p = eye + *t * d, n = (p - white).normalized();
                const Eigen::Vector3d to_lamp = lamp.position - p;
                const double expected = albedo / kPi * std::max(0.0, n.dot(to_lamp.normalized())) *
                                        (lamp.reference_distance * lamp.reference_distance) / to_lamp.squaredNorm();
                // The chrome ball may shadow a few points facing it; compare the rest.
                if (image.at(x, y, 0) > 0.0f || expected == 0.0) {
                    worst = std::max(worst, std::abs(image.at(x, y, 0) - expected));
                    ++lit;
                }
            } else if (ray_sphere(eye, d, chrome, radius)) {
                // The lamp's radiance, 100^2 / (pi 15^2) = 14, over the white ball mirrored.
                const double v = image.at(x, y, 0) > 1.0f ? image.at(x, y, 0) : 0.0;
                peak = std::max(peak, v);
                sum += v;
                sx += v * (x + 0.5);
                sy += v * (y + 0.5);
            }
        }
    EXPECT_GT(lit, 700);
    EXPECT_LT(worst, 1e-5);
    // The mirror point: its normal halves the directions to the eye and to the lamp.
    Eigen::Vector3d p = chrome + radius * Eigen::Vector3d::UnitZ();
    for (int i = 0; i < 100; ++i)
        p = chrome + radius * ((eye - p).normalized() + (lamp.position - p).normalized()).normalized();
    const Eigen::Vector2d expected = project(eye, target, Eigen::Vector3d::UnitY(), fov, w, h, p);
    ASSERT_GT(sum, 0);
    EXPECT_NEAR(sx / sum, expected.x(), 0.3);
    EXPECT_NEAR(sy / sum, expected.y(), 0.3);
    // Inside the lamp's disc the mirror shows its radiance (one camera ray a pixel).
    EXPECT_NEAR(peak, 1e4 / (kPi * 15.0 * 15.0), 1e-4 * peak);
}

TEST(Stage, GlassSlabShiftsAnEdgeAsSnellPredicts) {
    // A white card covers x < 0; a tilted glass slab above it displaces its edge.
    // The image spans x in [-25, 25] mm at the card, 0.31 mm per pixel: every camera ray
    // crosses the slab's top and bottom faces, and the lateral shift of a 20 mm slab at 30
    // degrees, 20 sin(30 - 19.47) / cos(19.47) = 3.9 mm, spans a dozen pixels.
    const Eigen::Vector3d eye(0, 0, 2000), target(0, 0, 0);
    const double tilt = degrees_to_radians(30.0), ior = 1.5;
    const int w = 160, h = 8;
    const double fov = radians_to_degrees(2 * std::atan(25.0 / 2000.0 * h / w));
    const Scene scene = scene_from(camera_toml(eye, target, fov, w, h, 1) + R"(
[kernel]
profile = "directional"
[materials.white]
type = "diffuse"
albedo = [0.8, 0.8, 0.8]
[materials.glass]
type = "glass"
ior = 1.5
[[object]]
type = "card"
material = "white"
center_mm = [-60, 0, 0]
size_mm = [120, 120]
[[object]]
type = "box"
material = "glass"
center_mm = [0, 0, 40]
size_mm = [80, 80, 20]
rotate_deg = [0, 30, 0]
)");
    const LightStage stage(scene);
    const Image image = stage.render(Eigen::Vector3d::UnitZ());
    // The slab's faces: top and bottom planes, normal rotated about y.
    const Eigen::Vector3d n(std::sin(tilt), 0, std::cos(tilt));
    const Eigen::Vector3d top = Eigen::Vector3d(0, 0, 40) + 10 * n, bottom = Eigen::Vector3d(0, 0, 40) - 10 * n;
    int mismatches = 0, refraction_matters = 0, bright = 0;
    const int y = h / 2;
    for (int x = 0; x < w; ++x) {
        const Eigen::Vector3d d = pinhole_ray(eye, target, Eigen::Vector3d::UnitY(), fov, w, h, x + 0.5, y + 0.5);
        const Eigen::Vector3d entry = eye + ((top - eye).dot(n) / d.dot(n)) * d;
        const Eigen::Vector3d inside = snell(d, n, 1.0, ior);
        const Eigen::Vector3d exit = entry + ((bottom - entry).dot(n) / inside.dot(n)) * inside;
        const Eigen::Vector3d out = snell(inside, n, ior, 1.0);
        const Eigen::Vector3d floor = exit + (-exit.z() / out.z()) * out;
        const Eigen::Vector3d straight = eye + (-eye.z() / d.z()) * d;
        // Both crossings inside the faces' 80 mm extent (no ray passes through a side face).
        const Eigen::Vector3d across(std::cos(tilt), 0, -std::sin(tilt));
        ASSERT_LT(std::abs((entry - top).dot(across)), 40);
        ASSERT_LT(std::abs((exit - bottom).dot(across)), 40);
        const bool expected = floor.x() < 0;
        refraction_matters += expected != (straight.x() < 0);
        const bool rendered = image.at(x, y, 0) > 0.3 * 0.8 / kPi;
        bright += rendered;
        mismatches += rendered != expected;
    }
    EXPECT_GE(refraction_matters, 8);  // the shift spans many pixels
    EXPECT_GT(bright, 40);
    EXPECT_LE(mismatches, 1);
}

TEST(Stage, GlassAbsorbsPerBeerLambert) {
    // A coloured slab at normal incidence between the camera (and the light) and a card:
    // both the camera path and the shadow ray cross 20 mm of glass.
    const Eigen::Vector3d eye(0, 0, 1000), target(0, 0, 0);
    const Scene scene = scene_from(camera_toml(eye, target, 2, 16, 16, 1) + R"(
[kernel]
profile = "directional"
[materials.white]
type = "diffuse"
albedo = [0.8, 0.8, 0.8]
[materials.tinted]
type = "glass"
ior = 1.5
absorption_per_mm = [0.0, 0.02, 0.05]
[[object]]
type = "card"
material = "white"
center_mm = [0, 0, 0]
size_mm = [200, 200]
[[object]]
type = "box"
material = "tinted"
center_mm = [0, 0, 30]
size_mm = [200, 200, 20]
)");
    const Image image = LightStage(scene).render(Eigen::Vector3d::UnitZ());
    const double fresnel = 1 - 0.04;
    for (int c = 0; c < 3; ++c) {
        const double sigma = c == 0 ? 0.0 : (c == 1 ? 0.02 : 0.05);
        const double one_way = fresnel * fresnel * std::exp(-sigma * 20);
        // Inter-reflections inside the slab add at most a few 0.04^2 terms.
        EXPECT_NEAR(image.at(8, 8, c), 0.8 / kPi * one_way * one_way, 3e-3 * 0.8 / kPi) << c;
    }
}

TEST(Stage, WideKernelBlursTheShadowEdgeByItsAngularSize) {
    // A horizontal occluder at height 50 mm covers x < -20; the light leans toward -x by 30
    // degrees, so the shadow edge lies near x = -20 + 50 tan 30 on the floor.
    const Eigen::Vector3d eye(20, 0, 3000), target(20, 0, 0);
    const double fov = 0.6, height = 50, beta = degrees_to_radians(30.0);
    const int w = 200, h = 16;
    auto render = [&](const std::string& kernel) {
        const Scene scene = scene_from(camera_toml(eye, target, fov, w, h, 16) + kernel + R"(
[materials.white]
type = "diffuse"
albedo = [1, 1, 1]
[[object]]
type = "card"
material = "white"
center_mm = [0, 0, 0]
size_mm = [600, 600]
[[object]]
type = "card"
material = "white"
center_mm = [-85, 0, 50]
size_mm = [130, 400]
)");
        return LightStage(scene).render(Eigen::Vector3d(-std::sin(beta), 0, std::cos(beta)));
    };
    // Expected radiance on the floor at x: (1/pi) * integral of K(w) w_z over the directions
    // that pass the occluder's edge, by a polar quadrature of the kernel around its centre.
    auto expected_profile = [&](const LightKernel& kernel, double x) {
        const Eigen::Vector3d d(-std::sin(beta), 0, std::cos(beta));
        Eigen::Vector3d b1 = Eigen::Vector3d::UnitY(), b2 = d.cross(b1);
        double lit = 0, total = 0;
        const int na = 64, np = 64;
        for (int i = 0; i < na; ++i) {
            const double a = (i + 0.5) * kernel.radius / na;
            for (int j = 0; j < np; ++j) {
                const double phi = (j + 0.5) * 2 * kPi / np;
                const Eigen::Vector3d wdir = std::cos(a) * d + std::sin(a) * (std::cos(phi) * b1 + std::sin(phi) * b2);
                const double weight = profile(kernel, a) * std::sin(a);
                total += weight;
                const double cross_x = x + height * wdir.x() / wdir.z();
                if (!(cross_x > -150 && cross_x < -20)) lit += weight * wdir.z();
            }
        }
        return lit / total / kPi;
    };
    // Tabulated once per kernel at 0.1 mm (a tenth of a pixel), interpolated linearly.
    auto tabulate = [&](const LightKernel& kernel) {
        std::vector<double> table;
        for (int i = 0; i <= 1200; ++i) table.push_back(expected_profile(kernel, -20 + 0.1 * i));
        return [table](double x) {
            const double at = std::clamp((x + 20) / 0.1, 0.0, static_cast<double>(table.size()) - 1.001);
            const auto i = static_cast<std::size_t>(at);
            return table[i] + (table[i + 1] - table[i]) * (at - static_cast<double>(i));
        };
    };
    const LightKernel narrow = LightKernel::narrow(), wide = LightKernel::wide();
    const Image narrow_image = render("[kernel]\nprofile = \"constant\"\nradius_deg = 2\nshadow_samples = 8\n");
    const Image wide_image = render("[kernel]\nprofile = \"smooth\"\nradius_deg = 15\nshadow_samples = 8\n");
    auto width_10_90 = [&](const std::function<double(double)>& f, double plateau) {
        double x10 = 1e9, x90 = 1e9;
        for (double x = -15; x < 60; x += 0.01) {
            if (f(x) >= 0.1 * plateau && x10 > 1e8) x10 = x;
            if (f(x) >= 0.9 * plateau && x90 > 1e8) x90 = x;
        }
        return x90 - x10;
    };
    for (const auto& [kernel, image] : {std::pair{narrow, &narrow_image}, std::pair{wide, &wide_image}}) {
        const auto expected = tabulate(kernel);
        const double plateau = expected(80);
        double worst = 0;
        std::vector<double> xs, row;
        for (int x = 0; x < w; ++x) {
            const Eigen::Vector3d d = pinhole_ray(eye, target, Eigen::Vector3d::UnitY(), fov, w, h, x + 0.5, h / 2.0);
            const double floor_x = (eye + (-eye.z() / d.z()) * d).x();
            if (floor_x < -15) continue;  // hidden under the occluder
            double mean = 0;
            for (int y = 0; y < h; ++y) mean += image->at(x, y, 0);
            mean /= h;
            xs.push_back(floor_x);
            row.push_back(mean);
            worst = std::max(worst, std::abs(mean - expected(floor_x)));
        }
        EXPECT_LT(worst, 0.04 * plateau) << to_string(kernel.profile);
        // Penumbra width of the render (linear interpolation of the row) against theory.
        auto rendered = [&](double x) {
            for (std::size_t i = 1; i < xs.size(); ++i)
                if (xs[i] >= x) return row[i - 1] + (row[i] - row[i - 1]) * (x - xs[i - 1]) / (xs[i] - xs[i - 1]);
            return row.back();
        };
        const double theory = width_10_90(expected, plateau);
        EXPECT_NEAR(width_10_90(rendered, plateau), theory, 1.5 * (xs[1] - xs[0]) + 0.05 * theory);
        if (kernel.profile == KernelProfile::Smooth) {
            // Geometric spread of a 15-degree kernel's half-maximum cone over 50 mm.
            EXPECT_GT(theory, height * (std::tan(beta + kernel.radius / 2) - std::tan(beta - kernel.radius / 2)) * 0.5);
        } else {
            EXPECT_LT(theory, height * (std::tan(beta + kernel.radius) - std::tan(beta - kernel.radius)));
        }
    }
}

// ---- determinism ----

std::string small_spheres_scene() {
    return "seed = 7\n" + camera_toml({0, 0, 600}, {0, 0, 0}, 15, 40, 24, 3) + R"(
[kernel]
profile = "smooth"
radius_deg = 15
shadow_samples = 3
[materials.card]
type = "diffuse"
albedo = [0.8, 0.8, 0.8]
checker_mm = 15
[materials.gloss]
type = "glossy"
albedo = [0.5, 0.1, 0.1]
roughness = 0.2
[materials.glass]
type = "glass"
ior = 1.5
absorption_per_mm = [0, 0.01, 0.02]
[materials.chrome]
type = "mirror"
[[object]]
type = "card"
material = "card"
center_mm = [0, 0, 0]
size_mm = [300, 200]
[[object]]
type = "sphere"
material = "gloss"
center_mm = [-40, 0, 20]
radius_mm = 20
[[object]]
type = "cylinder"
material = "glass"
base_mm = [10, 0, 0]
radius_mm = 15
height_mm = 40
[[object]]
type = "sphere"
material = "chrome"
center_mm = [50, 10, 15]
radius_mm = 15
)";
}

TEST(Stage, RendersAreBitIdenticalRunToRunAndAcrossThreadCounts) {
    const Scene scene = scene_from(small_spheres_scene());
    const Eigen::Vector3d light = Eigen::Vector3d(0.4, 0.3, 0.8).normalized();
    const Image first = LightStage(scene).render(light);
    const Image second = LightStage(scene).render(light);
    EXPECT_EQ(first, second);
    {
        tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
        EXPECT_EQ(LightStage(scene).render(light), first);
    }
    Scene reseeded = scene;
    reseeded.seed = 8;
    EXPECT_NE(LightStage(reseeded).render(light), first);
    for (const float v : first.samples()) ASSERT_TRUE(std::isfinite(v));
}

TEST(Stage, ViewsRecordDirectionsInTheirOwnFrame) {
    Scene scene = scene_from(small_spheres_scene() + R"(
[[camera]]
position_mm = [400, 0, 450]
)");
    ASSERT_EQ(scene.cameras.size(), 2u);
    const LightStage second(scene, 1);
    // A light sitting at the second camera is straight "toward the camera" in its frame.
    const Eigen::Vector3d at_camera = Eigen::Vector3d(400, 0, 450).normalized();
    EXPECT_LT((second.to_view_frame() * at_camera - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
    const ReflectanceField field = render_field(second, {at_camera}, scene.kernel);
    EXPECT_LT((field.directions[0] - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
    ASSERT_EQ(field.kernel_radii.size(), 1u);
    EXPECT_DOUBLE_EQ(field.kernel_radii[0], degrees_to_radians(15.0));
}

// ---- ray queries on analytic shapes ----

TEST(RayScene, CylinderHitsLieOnItsSurfaceWithOutwardNormals) {
    const Scene scene = scene_from(camera_toml({0, 0, 600}, {0, 0, 0}, 15, 8, 8, 1) + R"(
[materials.m]
type = "diffuse"
[[object]]
type = "cylinder"
material = "m"
base_mm = [5, -3, 2]
axis = [1, 2, 3]
radius_mm = 12
height_mm = 30
)");
    const RayScene rays(scene, ObjectFilter::All);
    const auto& c = std::get<CylinderShape>(scene.objects[0].shape);
    int hits = 0;
    for (int i = 0; i < 2000; ++i) {
        // Rays from a sphere of origins toward points near the cylinder's middle.
        const Eigen::Vector3d origin = 200 * direction_from_angles(std::acos(1 - 2 * ((i * 0.618034) - std::floor(i * 0.618034))), 2.4 * i);
        const Eigen::Vector3d aim = c.base + 15 * c.axis + Eigen::Vector3d(std::sin(i), std::cos(1.3 * i), std::sin(0.7 * i)) * 14;
        const Eigen::Vector3d d = (aim - origin).normalized();
        const auto hit = rays.intersect(origin, d, 0, 1e9);
        if (!hit) continue;
        ++hits;
        const Eigen::Vector3d p = origin + hit->t * d;
        const double along = (p - c.base).dot(c.axis);
        const double across = (p - c.base - along * c.axis).norm();
        const bool on_side = std::abs(across - c.radius) < 1e-4 && along > -1e-4 && along < c.height + 1e-4;
        const bool on_cap = (std::abs(along) < 1e-4 || std::abs(along - c.height) < 1e-4) && across < c.radius + 1e-4;
        EXPECT_TRUE(on_side || on_cap) << along << " " << across;
        EXPECT_LT(d.dot(hit->normal), 0.0);  // seen from outside: first hit faces the ray
        EXPECT_TRUE(rays.occluded(origin, d, 0, 1e9));
    }
    EXPECT_GT(hits, 1000);
}

// ---- scene files ----

TEST(SceneFile, ErrorsNameFileLineAndKey) {
    const std::string camera = camera_toml({0, 0, 600}, {0, 0, 0}, 15, 8, 8, 1);
    const std::string material = "[materials.m]\ntype = \"diffuse\"\n";
    const int object_line = 11;  // camera (7 lines), material (2), [[object]], then keys
    auto error = [&](const std::string& object) {
        return error_of([&] { scene_from(camera + material + "[[object]]\n" + object); });
    };
    EXPECT_THAT(error("type = \"sphere\"\nmaterial = \"m\"\ncenter_mm = [0, 0, 0]\nradius_mm = 5\nraduis_mm = 3\n"),
                MatchesRegex("test\\.toml:" + std::to_string(object_line + 4) +
                             ":[0-9]+: object\\[0\\]\\.raduis_mm: unknown key.*"));
    EXPECT_THAT(error("type = \"sphere\"\nmaterial = \"m\"\ncenter_mm = [0, 0, 0]\nradius_cm = 5\n"),
                MatchesRegex("test\\.toml:" + std::to_string(object_line + 3) +
                             ":[0-9]+: object\\[0\\]\\.radius_cm: wrong unit: expected 'radius_mm'.*"));
    EXPECT_THAT(error("type = \"mesh\"\nmaterial = \"m\"\nfile = \"no_such_mesh.obj\"\n"),
                MatchesRegex("test\\.toml:" + std::to_string(object_line + 2) +
                             ":[0-9]+: object\\[0\\]\\.file: mesh 'no_such_mesh.obj': .*cannot open.*"));
    EXPECT_THAT(error("type = \"sphere\"\nmaterial = \"wood\"\ncenter_mm = [0, 0, 0]\nradius_mm = 5\n"),
                MatchesRegex("test\\.toml:" + std::to_string(object_line + 1) +
                             ":[0-9]+: object\\[0\\]\\.material: no material named 'wood' \\(defined: m\\)"));
    EXPECT_THAT(error_of([&] {
                    scene_from(camera + "[materials.m]\ntype = \"velvet\"\n[[object]]\ntype = \"sphere\"\n");
                }),
                MatchesRegex("test\\.toml:9:[0-9]+: materials\\.m\\.type: .*velvet.*"));
    EXPECT_THAT(error_of([&] {
                    scene_from(camera + "[materials.m]\ntype = \"glossy\"\nroughness = 2\n[[object]]\n");
                }),
                HasSubstr("test.toml:10:"));
    EXPECT_THAT(error_of([&] {
                    scene_from(camera + "[materials.g]\ntype = \"glass\"\nior = 1.5\n[[object]]\ntype = \"card\"\n"
                               "material = \"g\"\ncenter_mm = [0, 0, 0]\nsize_mm = [1, 1]\n");
                }),
                HasSubstr("glass needs a closed solid"));
    EXPECT_THAT(error("type = \"sphere\"\nmaterial = \"m\"\ncenter_mm = [0, 0]\nradius_mm = 5\n"),
                HasSubstr("center_mm: expected an array of 3 numbers"));
    // A card's size is bounded as positions are: one of 1e300 mm loaded, and Embree aborted
    // on its first shadow ray (fuzz/fuzz_scene.cpp, scene_render).
    EXPECT_THAT(error("type = \"card\"\nmaterial = \"m\"\ncenter_mm = [0, 0, 0]\nsize_mm = [1e300, 1]\n"),
                HasSubstr("object[0].size_mm: value 1e+300 is outside the allowed range [-1e+09, 1e+09]"));
    EXPECT_THAT(error("type = \"plane\"\nmaterial = \"m\"\npoint_mm = [0, 0, 0]\nsize_mm = [1, -1]\n"),
                HasSubstr("object[0].size_mm: expected two positive numbers"));
}

TEST(SceneFile, BundledScenesLoad) {
    for (const char* name : {"bottle", "spheres", "figure"}) {
        const Scene scene = load_scene(std::filesystem::path(RFD_SOURCE_DIR) / "scenes" / (std::string(name) + ".toml"));
        EXPECT_FALSE(scene.objects.empty()) << name;
        EXPECT_EQ(scene.cameras.size(), 1u) << name;
        // A thumbnail under a light between the camera and the zenith: finite, non-negative,
        // and something lit (the scene's objects are in view).
        Scene thumbnail = scene;
        thumbnail.cameras[0].width = 32;
        thumbnail.cameras[0].height = 16;
        thumbnail.samples_per_pixel = 1;
        const Image image = LightStage(thumbnail).render(Eigen::Vector3d(0.2, 0.5, 0.8).normalized());
        double total = 0;
        for (const float v : image.samples()) {
            ASSERT_TRUE(std::isfinite(v) && v >= 0.0f) << name;
            total += v;
        }
        EXPECT_GT(total / static_cast<double>(image.samples().size()), 0.02) << name;
    }
}

TEST(SceneFile, ImageTextureMapsTopLeftToTopLeft) {
    TempDir dir;
    Image texture(2, 2, 3);
    const float colours[4][3] = {{0.9f, 0.1f, 0.1f}, {0.1f, 0.9f, 0.1f}, {0.1f, 0.1f, 0.9f}, {0.9f, 0.9f, 0.1f}};
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 2; ++x)
            for (int c = 0; c < 3; ++c) texture.at(x, y, c) = colours[y * 2 + x][c];
    write_image(dir / "texture.exr", texture);
    // The card fills the image exactly.
    const double fov = radians_to_degrees(2 * std::atan(60.0 / 1000.0));
    const Scene scene = scene_from(camera_toml({0, 0, 1000}, {0, 0, 0}, fov, 32, 32, 1) + R"(
[kernel]
profile = "directional"
[materials.photo]
type = "diffuse"
texture = "texture.exr"
[[object]]
type = "card"
material = "photo"
center_mm = [0, 0, 0]
size_mm = [120, 120]
)", dir.path());
    const Image image = LightStage(scene).render(Eigen::Vector3d::UnitZ());
    // Texel centres sit at a quarter of the card: sample there (pixels 8 and 24).
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 2; ++x)
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(image.at(8 + 16 * x, 8 + 16 * y, c), colours[y * 2 + x][c] / kPi, 0.02)
                    << x << " " << y << " " << c;
}

// A small closed mesh (an octahedron with one face split into a quad-free fan), written
// as OBJ with quads and as PLY with the same faces.
void write_mesh_files(const std::filesystem::path& dir) {
    std::ofstream obj(dir / "shape.obj");
    obj << "# octahedron\nv 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n"
           "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";
    obj.close();
    std::ofstream ply(dir / "shape.ply");
    ply << "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
           "element face 8\nproperty list uchar int vertex_indices\nend_header\n"
           "1 0 0\n-1 0 0\n0 1 0\n0 -1 0\n0 0 1\n0 0 -1\n"
           "3 0 2 4\n3 2 1 4\n3 1 3 4\n3 3 0 4\n3 2 0 5\n3 1 2 5\n3 3 1 5\n3 0 3 5\n";
}

TEST(SceneFile, ObjAndPlyLoadTheSameMesh) {
    TempDir dir;
    write_mesh_files(dir.path());
    const MeshShape from_obj = read_mesh(dir / "shape.obj");
    const MeshShape from_ply = read_mesh(dir / "shape.ply");
    EXPECT_EQ(from_obj.positions.size(), 6u);
    EXPECT_EQ(from_obj.triangles.size(), 8u);
    EXPECT_TRUE(from_obj == from_ply);
    // Winding: every face's normal points away from the centre (a closed solid).
    for (const auto& t : from_obj.triangles) {
        const Eigen::Vector3f n = (from_obj.positions[t[1]] - from_obj.positions[t[0]])
                                      .cross(from_obj.positions[t[2]] - from_obj.positions[t[0]]);
        EXPECT_GT(n.dot(from_obj.positions[t[0]]), 0.0f);
    }
    auto scene_with = [&](const std::string& file) {
        return scene_from(camera_toml({0, 0, 300}, {0, 0, 0}, 10, 24, 24, 2) + R"(
[materials.m]
type = "glossy"
albedo = [0.5, 0.5, 0.5]
roughness = 0.3
[[object]]
type = "mesh"
material = "m"
file = ")" + file + R"("
scale = 20
rotate_deg = [10, 20, 30]
)", dir.path());
    };
    const Eigen::Vector3d light = Eigen::Vector3d(0.2, 0.5, 0.8).normalized();
    const Image a = LightStage(scene_with("shape.obj")).render(light);
    const Image b = LightStage(scene_with("shape.ply")).render(light);
    EXPECT_EQ(a, b);
    double total = 0;
    for (const float v : a.samples()) total += v;
    EXPECT_GT(total, 1.0);  // the mesh is there and lit
    EXPECT_THAT(error_of([&] { read_mesh(dir / "missing.ply"); }), HasSubstr("missing.ply: cannot open"));
    std::ofstream(dir / "empty.obj") << "# nothing\n";
    EXPECT_THAT(error_of([&] { read_mesh(dir / "empty.obj"); }), HasSubstr("empty.obj"));
}

}  // namespace
}  // namespace rfd::relight
