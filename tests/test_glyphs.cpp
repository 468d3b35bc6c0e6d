// Text masks: ink where the glyph is, centred, filling what was asked.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "patterns/glyphs.hpp"
#include "tests/support/error_of.hpp"

namespace rfd::patterns {
namespace {

struct InkBox {
    int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
    double coverage = 0;
};

InkBox ink_box(const Image& mask) {
    InkBox box;
    for (int y = 0; y < mask.height(); ++y)
        for (int x = 0; x < mask.width(); ++x) {
            const float v = mask.at(x, y, 0);
            box.coverage += v;
            if (v > 0.5f) {
                box.x0 = std::min(box.x0, x);
                box.x1 = std::max(box.x1, x);
                box.y0 = std::min(box.y0, y);
                box.y1 = std::max(box.y1, y);
            }
        }
    return box;
}

TEST(TextMask, GlyphIsCentredAndFillsTheAskedFraction) {
    const Image mask = text_mask("I", 100, 80, 0.5);
    const InkBox box = ink_box(mask);
    ASSERT_GE(box.x1, 0) << "no ink";
    // "I" is a vertical bar: its height sets the scale (half of the smaller side, 40 px).
    EXPECT_NEAR(box.y1 - box.y0 + 1, 40, 2);
    EXPECT_NEAR(0.5 * (box.x0 + box.x1), 49.5, 1.5);
    EXPECT_NEAR(0.5 * (box.y0 + box.y1), 39.5, 1.5);
    EXPECT_LT(box.x1 - box.x0, 20);
}

TEST(TextMask, DifferentLettersDifferAndBackgroundIsBlack) {
    const Image s = text_mask("S", 64, 64);
    const Image o = text_mask("O", 64, 64);
    EXPECT_NE(s, o);
    EXPECT_EQ(s.at(0, 0, 0), 0.0f);
    EXPECT_EQ(s.at(63, 63, 0), 0.0f);
    for (float v : s.samples()) {
        EXPECT_GE(v, 0.0f);
        EXPECT_LE(v, 1.0f);
    }
}

TEST(TextMask, RejectsEmptyTextAndSize) {
    EXPECT_THAT(rfd::testing::error_of([] { text_mask("", 10, 10); }), ::testing::HasSubstr("empty text"));
    EXPECT_THAT(rfd::testing::error_of([] { text_mask("A", 0, 10); }), ::testing::HasSubstr("must be positive"));
}

}  // namespace
}  // namespace rfd::patterns
