// The predicted display as a field (predict/rti_export.hpp): directions spread over a cone
// about the display's axis, and one picture per direction that is exactly the simulator's
// for that light alone.

#include <cmath>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/sphere.hpp"
#include "core/units.hpp"
#include "optics/design.hpp"
#include "predict/rti_export.hpp"
#include "tests/support/error_of.hpp"

namespace rfd::predict {
namespace {

using ::testing::HasSubstr;
using rfd::testing::error_of;

TEST(ConeDirections, FillTheConeAndRepeatForASeed) {
    const double half_angle = degrees_to_radians(12.0);
    const std::vector<Eigen::Vector3d> directions = cone_directions(40, half_angle, 3);
    ASSERT_EQ(directions.size(), 40u);
    double widest = 0.0;
    for (const Eigen::Vector3d& d : directions) {
        EXPECT_NEAR(d.norm(), 1.0, 1e-12);
        widest = std::max(widest, angles_of(d).theta);
    }
    EXPECT_LE(widest, half_angle + 1e-12);
    EXPECT_GT(widest, 0.8 * half_angle);  // the pattern reaches out to the cone's edge
    EXPECT_EQ(cone_directions(40, half_angle, 3), directions);
    EXPECT_THAT(error_of([] { cone_directions(4, degrees_to_radians(95.0), 1); }), HasSubstr("half angle"));
}

TEST(PredictedField, EachPictureIsTheSimulatorsUnderThatLightAlone) {
    const optics::Design design = optics::load_design(std::string(RFD_SOURCE_DIR) + "/designs/design2.toml");
    const optics::DisplaySimulator simulator(design);
    // A random grey raster over the array.
    std::mt19937 random(5);
    std::uniform_real_distribution<float> grey(0.0f, 1.0f);
    const int width = 120, height = 120;
    std::vector<float> values(static_cast<std::size_t>(width * height));
    for (float& v : values) v = grey(random);
    const optics::RasterTransparency pattern(width, height, 1, 0.25, 0.25, std::move(values));
    optics::SimulationOptions options;
    options.rays_per_side = 4;
    const std::vector<Eigen::Vector3d> toward = cone_directions(3, degrees_to_radians(8.0), 1);
    const relight::ReflectanceField shown = predicted_field(simulator, pattern, toward, options, true);
    ASSERT_EQ(shown.size(), 3u);
    for (std::size_t k = 0; k < toward.size(); ++k) {
        EXPECT_EQ(shown.directions[k], toward[k]);
        // The display meets the light travelling away from it: x and y reversed.
        const optics::DisplayLight light{{-toward[k].x(), -toward[k].y(), toward[k].z()}, {1, 1, 1}};
        EXPECT_EQ(shown.images[k], simulator.per_lenslet(simulator.simulate(pattern, {light}, options))) << k;
    }
    EXPECT_EQ(shown.width(), 6);
    EXPECT_EQ(shown.height(), 5);
    EXPECT_THAT(error_of([&] { predicted_field(simulator, pattern, {Eigen::Vector3d(0, 0.2, -1)}, options, true); }),
                HasSubstr("must shine from behind it"));
}

}  // namespace
}  // namespace rfd::predict
