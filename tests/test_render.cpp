// Relighting (thesis 4.2) against closed forms on an analytic Lambertian sphere.

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/render.hpp"
#include "tests/support/lambertian_sphere.hpp"

namespace rfd::relight {
namespace {

using rfd::testing::fibonacci_hemisphere;
using rfd::testing::lambertian_sphere_field;
using rfd::testing::sphere_normal;

constexpr int kSize = 48;
constexpr double kAlbedo = 0.8;

const ReflectanceField& dense_field() {
    static const ReflectanceField field = lambertian_sphere_field(fibonacci_hemisphere(400), kSize, kAlbedo);
    return field;
}

// Where all three interpolated directions light a pixel, f(w) = albedo/pi n.w is linear, so
// the relit value is exactly f at the chord point p = sum l_i d_i: |p| times the true value.
// Elsewhere (the terminator crosses the triangle) f is 1-Lipschitz in angle and the error is
// at most albedo/pi times the largest angle from d to a vertex used.
TEST(Render, DirectionalLightOnLambertianSphereMatchesClosedForm) {
    const ReflectanceField& field = dense_field();
    const SphericalInterpolator interp(field.directions);
    for (const auto& [theta, phi] : {std::pair{0.35, 0.4}, std::pair{1.0, -2.0}, std::pair{1.45, 2.5}}) {
        const Eigen::Vector3d d = direction_from_angles(theta, phi);
        const Image image = render(field, {DirectionalLight{d, Eigen::Vector3d::Ones()}});
        ASSERT_EQ(image.channels(), 1);
        const InterpolationWeights w = interp.weights(d);
        Eigen::Vector3d chord = Eigen::Vector3d::Zero();
        double reach = 0.0;
        for (std::size_t k = 0; k < w.count; ++k) {
            chord += w.weight[k] * field.directions[w.index[k]];
            reach = std::max(reach, angle_between(d, field.directions[w.index[k]]));
        }
        std::size_t linear_pixels = 0;
        for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x) {
                const auto n = sphere_normal(x, y, kSize);
                const double exact = n ? kAlbedo / kPi * std::max(0.0, n->dot(d)) : 0.0;
                const double relit = image.at(x, y, 0);
                if (!n) {
                    EXPECT_EQ(relit, 0.0);
                    continue;
                }
                bool all_lit = true;
                for (std::size_t k = 0; k < w.count; ++k) all_lit = all_lit && n->dot(field.directions[w.index[k]]) > 0.0;
                if (all_lit && w.count == 3) {
                    EXPECT_NEAR(relit, chord.norm() * exact, 2e-6) << x << "," << y;
                    ++linear_pixels;
                }
                EXPECT_LE(std::abs(relit - exact), kAlbedo / kPi * reach + 1e-6) << x << "," << y;
            }
        if (w.count == 3) {
            EXPECT_GT(linear_pixels, 100u);
        }
    }
}

// A constant sky L over the upper hemisphere on a Lambertian surface with normal n: the
// irradiance is pi L (1 + n_z) / 2 (the isotropic-sky view factor), so I = albedo L (1+n_z)/2.
TEST(Render, ConstantEnvironmentMapGivesSkyIrradiance) {
    const ReflectanceField& field = dense_field();
    const double sky = 2.0;
    const Image image = render(field, {EnvironmentMap{Image(64, 32, 1, static_cast<float>(sky))}});
    double worst = 0.0, sum = 0.0;
    std::size_t count = 0;
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            const auto n = sphere_normal(x, y, kSize);
            if (!n) continue;
            const double exact = kAlbedo * sky * (1.0 + n->z()) / 2.0;
            const double error = std::abs(image.at(x, y, 0) - exact) / (kAlbedo * sky);
            worst = std::max(worst, error);
            sum += error;
            ++count;
        }
    // Linear interpolation of a cosine over ~7-degree triangles: chord shrink about 0.2 %,
    // more where the terminator or the horizon's arc weights cut a triangle.
    EXPECT_LT(sum / static_cast<double>(count), 0.005);
    EXPECT_LT(worst, 0.02);
}

TEST(Render, LightFromBelowTheHorizonIsDropped) {
    const ReflectanceField& field = dense_field();
    Image env(32, 16, 1, 0.0f);
    for (int y = 8; y < 16; ++y)
        for (int x = 0; x < 32; ++x) env.at(x, y, 0) = 5.0f;  // only the lower half is bright
    const Image image = render(field, {EnvironmentMap{env}, DirectionalLight{direction_from_angles(1.8, 0.0)}});
    for (const float s : image.samples()) EXPECT_EQ(s, 0.0f);
}

// A disk of angular radius r, normalised to irradiance E: over the pixels it lights fully,
// I = albedo/pi E n.d (1 + cos r)/2 (the mean of cos alpha over the cap); as r -> 0 the
// directional light.
TEST(Render, DiskLightMatchesClosedFormAndTendsToDirectional) {
    const ReflectanceField& field = dense_field();
    const Eigen::Vector3d d = direction_from_angles(0.5, 1.0);
    const double r = degrees_to_radians(20.0);
    const Image disk = render(field, {DiskLight{d, r, Eigen::Vector3d::Ones()}});
    std::size_t checked = 0;
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            const auto n = sphere_normal(x, y, kSize);
            // Fully lit with margin: the cap and its triangles are on the lit side.
            if (!n || angle_between(*n, d) > 0.5 * kPi - r - 0.3) continue;
            const double exact = kAlbedo / kPi * n->dot(d) * (1.0 + std::cos(r)) / 2.0;
            EXPECT_NEAR(disk.at(x, y, 0), exact, 0.006 * kAlbedo / kPi) << x << "," << y;
            ++checked;
        }
    EXPECT_GT(checked, 200u);

    const Image directional = render(field, {DirectionalLight{d, Eigen::Vector3d::Ones()}});
    auto max_difference = [&](const Image& a) {
        double worst = 0.0;
        for (std::size_t k = 0; k < a.samples().size(); ++k)
            worst = std::max(worst, std::abs(static_cast<double>(a.samples()[k]) - directional.samples()[k]));
        return worst;
    };
    const double wide = max_difference(disk);
    const double small = max_difference(render(field, {DiskLight{d, 0.01, Eigen::Vector3d::Ones()}}));
    const double tiny = max_difference(render(field, {DiskLight{d, 1e-5, Eigen::Vector3d::Ones()}}));
    EXPECT_GT(wide, 0.01 * kAlbedo / kPi);
    EXPECT_LT(small, wide);
    EXPECT_LT(tiny, 1e-5);
}

TEST(Render, ColouredLightsAddUpPerChannel) {
    const ReflectanceField& field = dense_field();
    const Eigen::Vector3d d1 = direction_from_angles(0.4, 0.2), d2 = direction_from_angles(0.9, 2.0);
    const Image red = render(field, {DirectionalLight{d1, Eigen::Vector3d(1.0, 0.0, 0.0)}});
    const Image both = render(field, {DirectionalLight{d1, Eigen::Vector3d(1.0, 0.0, 0.0)},
                                      DirectionalLight{d2, Eigen::Vector3d(0.0, 0.5, 0.5)}});
    const Image grey2 = render(field, {DirectionalLight{d2, Eigen::Vector3d::Ones()}});
    ASSERT_EQ(red.channels(), 3);  // a grey field under coloured light turns coloured
    ASSERT_EQ(grey2.channels(), 1);
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            EXPECT_EQ(red.at(x, y, 1), 0.0f);
            EXPECT_EQ(both.at(x, y, 0), red.at(x, y, 0));
            EXPECT_NEAR(both.at(x, y, 1), 0.5f * grey2.at(x, y, 0), 1e-7);
            EXPECT_EQ(both.at(x, y, 1), both.at(x, y, 2));
        }
    // Deterministic: the same bits twice.
    EXPECT_EQ(render(field, {EnvironmentMap{Image(16, 8, 3, 0.3f)}}), render(field, {EnvironmentMap{Image(16, 8, 3, 0.3f)}}));
}

TEST(Render, NearestUsesOneImage) {
    const ReflectanceField& field = dense_field();
    const SphericalInterpolator interp(field.directions);
    const Eigen::Vector3d d = direction_from_angles(0.7, -0.4);
    const auto k = light_coefficients(interp, {DirectionalLight{d, Eigen::Vector3d::Ones()}}, Interpolation::Nearest);
    EXPECT_EQ(k.nonzero, 1u);
    const Image image = relight(field, k);
    const std::size_t nearest = interp.weights(d, Interpolation::Nearest).index[0];
    EXPECT_EQ(image, field.images[nearest]);
}

TEST(Render, BadLightsAreInputErrors) {
    const ReflectanceField& field = dense_field();
    EXPECT_THROW(render(field, {DiskLight{Eigen::Vector3d::UnitZ(), 0.0, Eigen::Vector3d::Ones()}}), InputError);
    EXPECT_THROW(render(field, {DiskLight{Eigen::Vector3d::UnitZ(), 2.0, Eigen::Vector3d::Ones()}}), InputError);
    EXPECT_THROW(render(field, {EnvironmentMap{Image(8, 4, 2, 1.0f)}}), InputError);
    EXPECT_THROW(render(field, {EnvironmentMap{Image(8, 4, 1, -1.0f)}}), InputError);
    EXPECT_THROW(render(field, {DirectionalLight{Eigen::Vector3d::UnitZ(), Eigen::Vector3d(1, -1, 1)}}), InputError);
}

}  // namespace
}  // namespace rfd::relight
