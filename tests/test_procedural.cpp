// Procedural test fields (thesis 8.2.4 and figure 8.15's shapes): what each light direction
// shows, where the directions are, and that guards keep their distance.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/sphere.hpp"
#include "core/units.hpp"
#include "patterns/glyphs.hpp"
#include "patterns/procedural.hpp"
#include "tests/support/error_of.hpp"

namespace rfd::patterns {
namespace {

double ink(const Image& image) {
    double sum = 0;
    for (float v : image.samples()) sum += v;
    return sum;
}

TEST(ProceduralField, LettersRunLeftToRightWithBlackGuardsAway) {
    ProceduralOptions options;
    options.text = "SIG08";
    options.spread_deg = 12;
    options.width = 40;
    options.height = 32;
    const relight::ReflectanceField field = procedural_field(options);
    ASSERT_GT(field.size(), 5u);
    const double spacing = degrees_to_radians(24.0 / 4);
    for (std::size_t k = 0; k < 5; ++k) {
        const Eigen::Vector3d& d = field.directions[k];
        EXPECT_NEAR(d.y(), 0.0, 1e-12);
        EXPECT_NEAR(std::asin(d.x()), degrees_to_radians(-12.0) + spacing * static_cast<double>(k), 1e-9);
        // The letter's mask in some colour: ink exactly where the mask has it.
        const Image mask = text_mask(std::string(1, options.text[k]), 40, 32);
        double mask_ink = 0, image_ink = 0;
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 40; ++x) {
                mask_ink += mask.at(x, y, 0);
                image_ink += std::max({field.images[k].at(x, y, 0), field.images[k].at(x, y, 1), field.images[k].at(x, y, 2)});
            }
        EXPECT_NEAR(image_ink, mask_ink, 1e-3 * mask_ink);
    }
    EXPECT_NE(field.images[0], field.images[1]);
    for (std::size_t g = 5; g < field.size(); ++g) {
        EXPECT_EQ(ink(field.images[g]), 0.0);
        for (std::size_t k = 0; k < 5; ++k) EXPECT_GE(angle_between(field.directions[g], field.directions[k]), spacing - 1e-12);
    }
}

TEST(ProceduralField, BarsAreHorizontalFromTheLeftAndVerticalFromTheRight) {
    ProceduralOptions options;
    options.kind = ProceduralKind::Bars;
    options.width = options.height = 50;
    const relight::ReflectanceField field = procedural_field(options);
    const Image& left = field.images[0];
    const Image& right = field.images[1];
    EXPECT_LT(field.directions[0].x(), 0.0);
    EXPECT_GT(field.directions[1].x(), 0.0);
    // Row 15 (v = 0.31) crosses the upper horizontal bar; column 25 the vertical one.
    EXPECT_EQ(left.at(10, 15, 0), 1.0f);
    EXPECT_EQ(left.at(40, 15, 0), 1.0f);
    EXPECT_EQ(left.at(25, 25, 0), 0.0f);
    EXPECT_EQ(right.at(25, 10, 0), 1.0f);
    EXPECT_EQ(right.at(25, 40, 0), 1.0f);
    EXPECT_EQ(right.at(10, 15, 0), 0.0f);
}

TEST(ProceduralField, DiamondsGrowAsTheLightMovesDownAndHollowSideways) {
    ProceduralOptions options;
    options.kind = ProceduralKind::Diamonds;
    options.diamond_steps = 3;
    options.width = options.height = 60;
    const relight::ReflectanceField field = procedural_field(options);
    // Grid order: row j (light from below to above), column i (left to right).
    auto at = [&](int i, int j) -> const Image& { return field.images[static_cast<std::size_t>(j * 3 + i)]; };
    EXPECT_LT(field.directions[0].y(), 0.0);  // j = 0: the light below
    EXPECT_GT(ink(at(1, 0)), 1.5 * ink(at(1, 2)));  // lower light, larger diamond
    EXPECT_GT(at(1, 1).at(30, 30, 0), 0.9f);        // centred light: solid
    EXPECT_LT(at(0, 1).at(30, 30, 0), 0.1f);        // from the side: hollow
    EXPECT_LT(at(2, 1).at(30, 30, 0), 0.1f);
    EXPECT_GT(ink(at(0, 1)), 0.0);
}

TEST(ProceduralField, RejectsBadOptions) {
    ProceduralOptions options;
    options.text = "";
    EXPECT_THAT(rfd::testing::error_of([&] { procedural_field(options); }), ::testing::HasSubstr("--text"));
    options.text = "A";
    options.spread_deg = 95;
    EXPECT_THAT(rfd::testing::error_of([&] { procedural_field(options); }), ::testing::HasSubstr("--spread"));
}

}  // namespace
}  // namespace rfd::patterns
