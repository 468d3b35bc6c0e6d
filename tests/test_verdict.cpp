// The verdict's rules: each call with the reason that decided it, PSNR against the field's
// brightest value (a direction where the field is dark is not a failure), and the edge
// cases where there is nothing to judge.

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "predict/verdict.hpp"

namespace rfd::predict {
namespace {

using ::testing::HasSubstr;

// A direction whose PSNR against a peak of 1 is `db`.
ComparedDirection direction(double angle, double db, bool crosstalk_free = true, bool inside = true, double peak = 1.0) {
    return {angle, inside, crosstalk_free, std::pow(10.0, -db / 10.0), peak};
}

VerdictInputs good_display() {
    VerdictInputs in;
    in.design = "test";
    in.field_of_view_deg = 24.0;
    in.crosstalk_free_cone_deg = 18.0;
    in.directions = {direction(0, 40), direction(5, 36), direction(11, 26, false)};
    in.tolerances = AssemblyTolerances{0.2, 0.6, 6000.0, 1.2};
    return in;
}

TEST(Verdict, GoWhenEveryRuleHolds) {
    const Verdict v = judge(good_display());
    EXPECT_EQ(v.call, Call::Go) << v.line();
    EXPECT_NEAR(*v.psnr_mean_crosstalk_free_db, 38.0, 1e-9);
    EXPECT_NEAR(*v.psnr_mean_in_fov_db, 34.0, 1e-9);
    EXPECT_NEAR(*v.psnr_min_in_fov_db, 26.0, 1e-9);
    EXPECT_EQ(v.directions_in_fov, 3);
    EXPECT_EQ(v.directions_crosstalk_free, 2);
    EXPECT_THAT(v.line(), HasSubstr("go: predicted 38.0 dB in the crosstalk-free cone"));
}

TEST(Verdict, EachRuleDecidesWithItsReason) {
    VerdictInputs poor = good_display();
    poor.directions = {direction(0, 18), direction(5, 15)};
    EXPECT_EQ(judge(poor).call, Call::NoGo);
    EXPECT_THAT(judge(poor).reason, HasSubstr("16.5 dB over the field of view"));

    VerdictInputs tight = good_display();
    tight.tolerances->shift_mm = 0.04;
    EXPECT_EQ(judge(tight).call, Call::Check);
    EXPECT_THAT(judge(tight).reason, HasSubstr("shift must stay under 0.04 mm"));
    tight.tolerances->shift_mm = 0.2;
    tight.tolerances->pitch_ppm = 300;
    EXPECT_THAT(judge(tight).reason, HasSubstr("moire sheet"));

    VerdictInputs mediocre = good_display();
    mediocre.directions = {direction(0, 28), direction(5, 26)};
    EXPECT_EQ(judge(mediocre).call, Call::Check);
    EXPECT_THAT(judge(mediocre).reason, HasSubstr("crosstalk-free cone shows the field at 27.0 dB"));

    VerdictInputs edge = good_display();
    edge.directions.push_back(direction(11.5, 12, false));
    EXPECT_EQ(judge(edge).call, Call::Check);
    EXPECT_THAT(judge(edge).reason, HasSubstr("at 11.5 deg from the axis the prediction falls to 12.0 dB"));

    VerdictInputs warned = good_display();
    warned.warnings = {"macro-pixels overlap", "another"};
    EXPECT_THAT(judge(warned).line(), HasSubstr("check: design warning: macro-pixels overlap (and 1 more)"));
}

// Design II always warns (its corrective pair magnifies each macro-pixel): the verdict on the
// field must still say whether the field shows well, apart from the design's own warning.
TEST(Verdict, TheFieldAndTheDesignAreJudgedApart) {
    VerdictInputs warned = good_display();
    warned.warnings = {"macro-pixels overlap"};
    const Verdict both = judge(warned);
    EXPECT_EQ(both.call, Call::Check);
    EXPECT_EQ(both.on_field.call, Call::Go);
    EXPECT_THAT(both.on_field.line(), HasSubstr("go: predicted 38.0 dB"));
    EXPECT_EQ(both.on_design.call, Call::Check);
    EXPECT_EQ(both.on_design.line(), "check: design warning: macro-pixels overlap");

    VerdictInputs poor = good_display();
    poor.directions = {direction(0, 18), direction(5, 15)};
    const Verdict bad_field = judge(poor);
    EXPECT_EQ(bad_field.on_field.call, Call::NoGo);
    EXPECT_EQ(bad_field.on_design.call, Call::Go);
    EXPECT_EQ(bad_field.on_design.line(), "go: no design warnings");
    EXPECT_EQ(bad_field.line(), bad_field.on_field.line());

    // Both good: the whole is go, its reason the field's and the design's.
    const Verdict good = judge(good_display());
    EXPECT_EQ(good.on_field.call, Call::Go);
    EXPECT_EQ(good.line(), good.on_field.line() + ", no design warnings");
}

// Tolerances in what a maker measures: 6000 ppm over a 150 mm print is 0.90 mm; 0.6 deg turns
// the corner of a 150 mm square (106.07 mm from its centre) by 1.1 mm.
TEST(Verdict, TolerancesAreSaidInMillimetresOverThePrint) {
    const AssemblyTolerances t{0.2, 0.6, 6000.0, 1.2};
    const std::string text = maker_tolerance_text(t, {"spacer"}, {150.0, 150.0});
    EXPECT_THAT(text, HasSubstr("shift 0.20 mm"));
    EXPECT_THAT(text, HasSubstr("rotation 0.60 deg (1.1 mm at the print's corner)"));
    EXPECT_THAT(text, HasSubstr("pitch 6000 ppm (the print's size within 0.90 mm over its 150 mm: print at 100 %"));
    EXPECT_THAT(text, HasSubstr("spacer 1.2 mm or more"));
    // Design IV's print spans its 7 x 7 macro-pixels, 34 mm apart.
    const Eigen::Vector2d extent = printed_extent_mm(optics::load_design(std::string(RFD_SOURCE_DIR) + "/designs/design4.toml"));
    EXPECT_DOUBLE_EQ(extent.x(), 7 * 34.0);
}

// The field dark in one direction (a letter field lights one letter per direction): a small
// error there is small against the field's brightest value, not against its own faint peak.
TEST(Verdict, ADarkDirectionIsJudgedAgainstTheFieldsBrightest) {
    VerdictInputs in = good_display();
    ComparedDirection dark = direction(3, 50);
    dark.peak = 1e-4;  // its own peak would make 50 dB into -30 dB
    in.directions.push_back(dark);
    const Verdict v = judge(in);
    EXPECT_EQ(v.call, Call::Go) << v.line();
    EXPECT_NEAR(*v.psnr_min_in_fov_db, 26.0, 1e-9);
}

TEST(Verdict, NothingToJudgeIsACheckNotAGo) {
    VerdictInputs outside = good_display();
    for (auto& d : outside.directions) d.inside_fov = false;
    EXPECT_EQ(judge(outside).call, Call::Check);
    EXPECT_THAT(judge(outside).reason, HasSubstr("no compared light lies inside the field of view"));
    VerdictInputs black = good_display();
    for (auto& d : black.directions) d.peak = 0.0;
    EXPECT_THAT(judge(black).reason, HasSubstr("black"));
    VerdictInputs exact = good_display();
    for (auto& d : exact.directions) d.mse = 0.0;
    EXPECT_EQ(judge(exact).call, Call::Go);
    EXPECT_EQ(*judge(exact).psnr_mean_in_fov_db, 100.0);
}

}  // namespace
}  // namespace rfd::predict
