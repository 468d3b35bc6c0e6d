// Advice before the long steps: the tilt that puts most of a capture's lights inside the
// display's range (against a count made independently with the exact optics), and the walk's
// case: a 321 px painting under a 48-light dome on Design II.

#include <cmath>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/units.hpp"
#include "optics/design_optics.hpp"
#include "patterns/advice.hpp"

#include "tests/support/bundled.hpp"

namespace rfd::patterns {
namespace {

using ::testing::HasSubstr;
using rfd::testing::bundled_design;
using rfd::testing::bundled_design_path;

Eigen::Vector3d from_angles(double theta_deg, double phi_deg) {
    const double t = degrees_to_radians(theta_deg), p = degrees_to_radians(phi_deg);
    return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

// A dome's lights: rings of 8, 16 and 24 at 20, 45 and 70 degrees from the zenith.
std::vector<Eigen::Vector3d> dome_lights() {
    std::vector<Eigen::Vector3d> lights;
    for (const auto& [theta, count] : {std::pair{20.0, 8}, std::pair{45.0, 16}, std::pair{70.0, 24}})
        for (int k = 0; k < count; ++k) lights.push_back(from_angles(theta, 360.0 * (k + 0.5) / count));
    return lights;
}

// The lights whose exact chief ray, entering the centre lenslet, lands inside its cell.
int exactly_inside(const optics::DesignOptics& optics, const std::vector<Eigen::Vector3d>& lights,
                   const AngularMapping& mapping) {
    int inside = 0;
    for (const auto& light : lights) {
        const Eigen::Vector3d d = mapping.display_direction(light);
        if (d.z() <= 0) continue;
        const auto landing = optics.land(d, optics.centre_cell(), optics::Model::Exact);
        if (landing.status == optics::RayStatus::Ok && landing.cell == optics.centre_cell()) ++inside;
    }
    return inside;
}

// Every whole-degree tilt whose range the lights surround holds at most `best` of them
// inside; returns how many such tilts there are.
int surrounded_tilts_holding_at_most(const optics::DesignOptics& optics, const std::vector<Eigen::Vector3d>& lights,
                                     int best) {
    int surrounded = 0;
    for (int tilt = -90; tilt <= 90; ++tilt) {
        AngularMapping mapping;
        mapping.tilt_deg = tilt;
        const LightsInRange at = lights_in_range(optics, lights, mapping);
        if (!at.covered) continue;
        EXPECT_LE(at.inside, best) << tilt;
        ++surrounded;
    }
    return surrounded;
}

TEST(Advice, TheBestTiltTakesInTheMostLights) {
    // A cluster of 25 lights within 25 degrees of a direction 40 degrees toward the field's
    // up, and a ring far from it: tilted 40 degrees up the display sees the cluster.
    std::vector<Eigen::Vector3d> lights;
    const Eigen::Vector3d centre = from_angles(40.0, 90.0);
    const Eigen::Vector3d across = centre.cross(Eigen::Vector3d::UnitX()).normalized();
    for (int i = -2; i <= 2; ++i)
        for (int j = -2; j <= 2; ++j) {
            const Eigen::Vector3d d = centre + std::tan(degrees_to_radians(12.0 * i)) * Eigen::Vector3d::UnitX() +
                                      std::tan(degrees_to_radians(12.0 * j)) * across;
            lights.push_back(d.normalized());
        }
    for (int k = 0; k < 12; ++k) lights.push_back(from_angles(80.0, 200.0 + 10.0 * k));
    const optics::DesignOptics optics(optics::with_lenslet_count(bundled_design(1), 5, 5));
    const TiltChoice best = best_tilt(optics, lights, {});
    EXPECT_TRUE(best.lights.covered);
    EXPECT_NEAR(best.tilt_deg, 40.0, 6.0);
    const LightsInRange level = lights_in_range(optics, lights, {});
    EXPECT_GT(best.lights.inside, level.inside);
    // The paraxial count against the exact optics' at the chosen tilt: a light or two at
    // the cell's rim may differ.
    AngularMapping tilted;
    tilted.tilt_deg = best.tilt_deg;
    EXPECT_NEAR(best.lights.inside, exactly_inside(optics, lights, tilted), 2);
    // No other whole-degree tilt that surrounds the range holds more lights.
    EXPECT_GT(surrounded_tilts_holding_at_most(optics, lights, best.lights.inside), 5);
}

TEST(Advice, APaintingUnderADomeOnDesignIIHearsOfDesignI) {
    // The walk's case: 321 x 321 pixels, 48 dome lights, Design II at tilt 0.
    const optics::Design design2 = bundled_design(2);
    const std::vector<std::string> bundled{bundled_design_path(1), bundled_design_path(2), bundled_design_path(3),
                                           bundled_design_path(4)};
    const Advice advice = advise(design2, bundled_design_path(2), bundled, "dome", 321, 321, dome_lights(), {});
    EXPECT_EQ(advice.chosen.elements_x, 6);
    EXPECT_EQ(advice.chosen.elements_y, 5);
    ASSERT_GE(advice.best, 0);
    EXPECT_EQ(advice.bundled[static_cast<std::size_t>(advice.best)].file, bundled_design_path(1));
    EXPECT_EQ(advice.bundled[static_cast<std::size_t>(advice.best)].shown_elements, 63 * 73);
    ASSERT_GE(advice.lines.size(), 3u);
    EXPECT_THAT(advice.lines.front(), HasSubstr("6 x 5 picture elements"));
    EXPECT_THAT(advice.lines.front(), HasSubstr("321 x 321 pixels"));
    EXPECT_THAT(advice.lines.back(), HasSubstr("design1"));
    // Designs III and IV are never suggested for a picture.
    for (const DesignFit& fit : advice.bundled)
        if (fit.kind == "III" || fit.kind == "IV") {
            EXPECT_EQ(fit.shown_elements, 0);
        }
}

TEST(Advice, OnADomeAutoTakesInTheMostLightsOfAnyTilt) {
    // The dome's 48 lights on Design II: the tilt auto chooses holds at least as many of
    // them inside a range they surround as any other whole-degree tilt, and more than none.
    const optics::DesignOptics optics(bundled_design(2));
    const std::vector<Eigen::Vector3d> lights = dome_lights();
    const TiltChoice best = best_tilt(optics, lights, {});
    ASSERT_TRUE(best.lights.covered);
    EXPECT_GT(surrounded_tilts_holding_at_most(optics, lights, best.lights.inside), 10);
    EXPECT_GE(best.lights.inside, 3);
    EXPECT_GT(best.lights.inside, lights_in_range(optics, lights, {}).inside);
}

TEST(Advice, TiltIsDegreesOrAuto) {
    EXPECT_FALSE(parse_tilt("auto", "--tilt"));
    EXPECT_EQ(*parse_tilt("45", "--tilt"), 45.0);
    EXPECT_THROW(parse_tilt("95", "--tilt"), InputError);
    EXPECT_THROW(parse_tilt("up", "--tilt"), InputError);
}

}  // namespace
}  // namespace rfd::patterns
