// Lights as the display meets them (predict/display_lights.hpp): named in the display's
// frame or the field's; checked against the field of view and the crosstalk onset;
// environment maps become one light per lit pixel carrying its power, from inside the
// pixel; maps finer than the display resolves (or than the ray budget) are box-filtered
// without losing power; light that meets the display from the front is dropped and
// counted; bad maps are refused with the pixel named.

#include <cmath>
#include <limits>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/sphere.hpp"
#include "core/text.hpp"
#include "core/units.hpp"
#include "optics/analysis.hpp"
#include "optics/design.hpp"
#include "predict/display_lights.hpp"
#include "tests/support/error_of.hpp"

namespace rfd::predict {
namespace {

using namespace rfd::patterns;
using ::testing::HasSubstr;
using rfd::testing::error_of;

double pixel_solid_angle(int width, int height, int v) {
    return (2.0 * kPi / width) * (std::cos(kPi * v / height) - std::cos(kPi * (v + 1) / height));
}

Eigen::Vector3d total(const std::vector<optics::DisplayLight>& lights) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const optics::DisplayLight& l : lights) sum += Eigen::Vector3d(l.colour[0], l.colour[1], l.colour[2]);
    return sum;
}

TEST(LightFrame, ALightOnTheDisplaysAxisIsTheTiltedAxisOfTheField) {
    const AngularMapping tilted{45.0, 0.0, 1.0};
    const relight::Light axis = relight::DirectionalLight{Eigen::Vector3d::UnitZ(), {1, 1, 1}};
    const auto field = std::get<relight::DirectionalLight>(light_in_field_frame(axis, LightFrame::Display, tilted));
    // --tilt 45 turns the display's axis toward the field's +y.
    EXPECT_LT((field.direction - Eigen::Vector3d(0, std::sqrt(0.5), std::sqrt(0.5))).norm(), 1e-12);
    EXPECT_LT((display_light(field, tilted).direction - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
    // The field frame is left as it is.
    EXPECT_EQ(std::get<relight::DirectionalLight>(light_in_field_frame(axis, LightFrame::Field, tilted)).direction,
              Eigen::Vector3d::UnitZ().eval());
}

TEST(LightFrame, DisplayFrameLightsMeetTheDisplayWhereTheySayUnderAnyMapping) {
    const AngularMapping mapping{30.0, -50.0, 1.5};
    for (const double theta_deg : {0.0, 5.0, 20.0, 40.0})
        for (const double phi_deg : {0.0, 70.0, 200.0}) {
            const Eigen::Vector3d toward = direction_from_angles(degrees_to_radians(theta_deg), degrees_to_radians(phi_deg));
            const relight::Light disc = relight::DiskLight{toward, 0.05, {1, 1, 1}};
            const optics::DisplayLight met = display_light(light_in_field_frame(disc, LightFrame::Display, mapping), mapping);
            // Travelling away from the light: x and y reversed, z kept.
            EXPECT_LT((met.direction - Eigen::Vector3d(-toward.x(), -toward.y(), toward.z())).norm(), 1e-9)
                << theta_deg << "," << phi_deg;
            EXPECT_NEAR(met.angular_radius_rad, 0.05, 1e-15);  // the disc keeps its size on the display
        }
}

TEST(LightCheck, WarnsOutsideTheFieldOfViewAndPastTheCrosstalkOnsetNamingTheAngles) {
    const optics::Design design = optics::load_design(std::string(RFD_SOURCE_DIR) + "/designs/design2.toml");
    const optics::DesignOptics optics(design);
    const optics::DesignSummary summary = optics::summarise(optics);
    const double wrap_x = *summary.wrap_over_exact_deg.at(0).second, onset_x = *summary.crosstalk_exact_deg.at(0).second;
    ASSERT_LT(onset_x, wrap_x);
    const AngularMapping none;
    // Along x (a display-frame light at phi 180 travels toward +x), the summary's angles.
    const auto at = [&](double theta_deg) {
        const relight::Light light =
            relight::DirectionalLight{direction_from_angles(degrees_to_radians(theta_deg), kPi), {1, 1, 1}};
        return check_light(optics, display_light(light, none), none);
    };
    const LightCheck on_axis = at(0.0);
    EXPECT_EQ(on_axis.warning(), "");
    const LightCheck inside = at(0.5 * onset_x);
    EXPECT_NEAR(*inside.wrap_over_deg, wrap_x, 1e-6);
    EXPECT_NEAR(*inside.crosstalk_deg, onset_x, 1e-6);
    EXPECT_EQ(inside.warning(), "");
    const LightCheck crossing = at(0.5 * (onset_x + wrap_x));
    EXPECT_TRUE(crossing.beyond_crosstalk_onset() && !crossing.outside_field_of_view());
    EXPECT_THAT(crossing.warning(), HasSubstr("beyond the crosstalk onset (" + format_fixed(onset_x, 1) + " deg"));
    const LightCheck outside = at(wrap_x + 3.0);
    EXPECT_THAT(outside.warning(), HasSubstr(format_fixed(wrap_x + 3.0, 1) + " deg from the display's axis, outside its "
                                             "field of view (wrap-over at " + format_fixed(wrap_x, 1)));
    EXPECT_NEAR(outside.display_theta_deg, wrap_x + 3.0, 1e-9);
    const LightCheck front = check_light(optics, {Eigen::Vector3d(0, 0.3, -1).normalized(), {1, 1, 1}}, none);
    EXPECT_THAT(front.warning(), HasSubstr("meets the display from the front"));
}

TEST(EnvironmentLights, OneLitPixelIsOneLightFromInsideItWithItsPower) {
    const int width = 32, height = 16, u = 20, v = 3;
    Image map(width, height, 3);
    map.at(u, v, 0) = 2.0f;
    map.at(u, v, 1) = 1.0f;
    const AngularMapping identity;
    EnvironmentSampling report;
    const auto lights = environment_lights(map, "sky.exr", identity, 0.0, 4096, &report);
    ASSERT_EQ(lights.size(), 1u);
    EXPECT_EQ(report.directions, 1u);
    EXPECT_EQ(report.reduction, 1);
    const double omega = pixel_solid_angle(width, height, v);
    EXPECT_NEAR(lights[0].colour[0], 2.0 * omega, 1e-12);
    EXPECT_NEAR(lights[0].colour[1], 1.0 * omega, 1e-12);
    EXPECT_EQ(lights[0].colour[2], 0.0);
    // Back in the field's frame, the direction lies inside the pixel.
    const SphericalAngles a = angles_of(identity.field_direction(lights[0].direction));
    EXPECT_GE(a.theta, kPi * v / height);
    EXPECT_LE(a.theta, kPi * (v + 1) / height);
    EXPECT_GE(a.phi, -kPi + 2 * kPi * u / width);
    EXPECT_LE(a.phi, -kPi + 2 * kPi * (u + 1) / width);
}

TEST(EnvironmentLights, BoxFilteringKeepsThePowerAndStopsAtTheDisplaysResolution) {
    const int width = 256, height = 128;
    Image map(width, height, 1);
    double expected = 0.0;
    for (int v = 0; v < height; ++v)
        for (int u = 0; u < width; ++u) {
            const float radiance = static_cast<float>(1.0 + std::sin(0.3 * u) * std::cos(0.2 * v));
            map.at(u, v, 0) = radiance;
            // Light behind the display under the identity mapping: the field's upper half.
            if (v < height / 2) expected += radiance * pixel_solid_angle(width, height, v);
        }
    const AngularMapping identity;
    EnvironmentSampling fine, coarse, budget;
    const auto all = environment_lights(map, "m", identity, 0.0, 1 << 20, &fine);
    EXPECT_EQ(fine.reduction, 1);
    EXPECT_EQ(fine.directions, static_cast<std::size_t>(width * height / 2));
    EXPECT_EQ(fine.in_front, static_cast<std::size_t>(width * height / 2));
    EXPECT_NEAR(total(all).x(), expected, 1e-9 * expected);
    // The display resolves 5 degrees: pixels of 1.4 degrees are filtered 4 x 4 (5.6 degrees).
    const auto filtered = environment_lights(map, "m", identity, degrees_to_radians(5.0), 1 << 20, &coarse);
    EXPECT_EQ(coarse.reduction, 4);
    EXPECT_EQ(coarse.sampled_width, width / 4);
    EXPECT_THAT(coarse.reason, HasSubstr("finer than the display resolves"));
    EXPECT_NEAR(total(filtered).x(), expected, 1e-9 * expected);
    // A budget of 600 directions: 64 x 32 has 1024 behind, 32 x 16 has 256.
    const auto few = environment_lights(map, "m", identity, 0.0, 600, &budget);
    EXPECT_EQ(budget.sampled_width, 32);
    EXPECT_EQ(few.size(), 256u);
    EXPECT_THAT(budget.reason, HasSubstr("ray budget"));
    EXPECT_NEAR(total(few).x(), expected, 1e-9 * expected);
}

TEST(EnvironmentLights, LightFromInFrontOfATiltedDisplayIsDropped) {
    // A uniform upper hemisphere in the field's frame, the display tilted by 45 degrees:
    // part of it lies in front of the display. What remains is what falls behind it.
    Image map(64, 32, 1);
    for (int v = 0; v < 16; ++v)
        for (int u = 0; u < 64; ++u) map.at(u, v, 0) = 1.0f;
    AngularMapping tilted;
    tilted.tilt_deg = 45.0;
    EnvironmentSampling report;
    const auto lights = environment_lights(map, "m", tilted, 0.0, 4096, &report);
    EXPECT_GT(report.in_front, 0u);
    EXPECT_EQ(report.directions + report.in_front, 64u * 16u);
    for (const optics::DisplayLight& l : lights) EXPECT_GT(l.direction.z(), 0.0);
    // Above the field's horizon and behind the display: two hemispheres whose poles are
    // 45 degrees apart meet in a lune of dihedral angle 135 degrees, of solid angle 2 (3 pi / 4).
    EXPECT_NEAR(total(lights).x(), 1.5 * kPi, 0.01 * kPi);
}

TEST(EnvironmentLights, BadMapsAreRefusedNamingThePixel) {
    Image nan_map(8, 4, 3);
    nan_map.at(5, 2, 1) = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THAT(error_of([&] { environment_lights(nan_map, "sky.exr", AngularMapping{}, 0.0, 100); }),
                HasSubstr("sky.exr: pixel (5, 2) channel 1 is NaN"));
    Image negative(8, 4, 1);
    negative.at(0, 3, 0) = -0.5f;
    EXPECT_THAT(error_of([&] { environment_lights(negative, "sky.exr", AngularMapping{}, 0.0, 100); }),
                HasSubstr("pixel (0, 3) channel 0 is -0.5"));
    EXPECT_THAT(error_of([&] { environment_lights(Image(8, 4, 2), "sky.exr", AngularMapping{}, 0.0, 100); }),
                HasSubstr("1 or 3 channels"));
}

}  // namespace
}  // namespace rfd::predict
