// rfd design tune: the tuner checked against the closed-form focal plane of a lenslet, on
// the thesis's Design III (the planes it holds, the light it gains), for determinism, for a
// target no spacing meets, and for the design file it writes.

#include <cmath>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/files.hpp"
#include "optics/analysis.hpp"
#include "optics/design.hpp"
#include "tune/tune.hpp"

#include "tests/support/bundled.hpp"

namespace rfd::tune {
namespace {

using ::testing::HasSubstr;
using rfd::testing::bundled_design;

const optics::PlanoConvex& first_lenslet(const optics::Design& design) {
    return std::get<optics::LensletArrayPart>(*design.planes.front().part).lens;
}

TEST(Tune, MovesThePatternIntoTheLensletsBackFocalPlane) {
    // Design I with its pattern (and the diffuser behind it) 1.3 mm too far back. A
    // plano-convex lenslet, curved side to the light, focuses f - t/n behind its flat,
    // f = R / (n - 1): the pattern must come back to z = t + f - t/n.
    optics::Design design = optics::with_lenslet_count(bundled_design(1), 5, 5);
    for (std::size_t k = 1; k < design.planes.size(); ++k) design.planes[k].z += 1.3;
    const optics::PlanoConvex& lens = first_lenslet(design);
    const double f = lens.radius / (lens.index - 1.0);
    const double focal_plane = lens.center_thickness + f - lens.center_thickness / lens.index;

    TuneSpec spec = default_spec(design, 5.0, 0.0);
    spec.free = {free_spacing(design, "B", 5.0, 0.0)};
    spec.planes = {"pattern-focus"};
    spec.tolerance_scale = 0.01;  // 0.6 um: the tuner must find the plane, not its tolerance
    spec.starts = 1;
    const TuneResult result = tune_design(design, spec);

    ASSERT_TRUE(result.feasible);
    EXPECT_FALSE(result.given_was_feasible);
    const double tolerance = 0.01 * 0.02 * f;
    EXPECT_NEAR(result.design.planes[1].z, focal_plane, tolerance + 1e-4);
    // The diffuser behind it moved with it: its spacing was not free.
    EXPECT_NEAR(result.design.planes[2].z - result.design.planes[1].z, design.planes[2].z - design.planes[1].z, 1e-9);
    EXPECT_EQ(result.design.planes[0].z, 0.0);
}

TEST(Tune, DesignIIIGainsLightWithItsThreeWorkingPlanesInPlace) {
    // The thesis's Design III keeps the meso lenslets at the main lens's focus, the pattern
    // at the main lens's image and in the projection lenslets' focal plane; tuned, every one
    // of them stays within the tolerance `design show` warns beyond, and more light leaves.
    const optics::Design design = bundled_design(3);
    TuneSpec spec = default_spec(design, 10.0, 0.0);
    spec.planes = {"meso-focus", "pattern-image", "pattern-focal"};
    spec.starts = 1;
    spec.evaluations_per_start = 100;
    const TuneResult result = tune_design(design, spec);
    ASSERT_TRUE(result.feasible);
    const auto summary = optics::summarise(optics::DesignOptics(result.design));
    int held = 0;
    for (const auto& check : summary.conjugates) {
        if (check.key == "projection-image") continue;
        EXPECT_LE(std::abs(check.plane_z - check.target_z), check.tolerance) << check.key;
        ++held;
    }
    EXPECT_EQ(held, 3);
    EXPECT_GT(summary.efficiency_on_axis, result.before.efficiency_on_axis + 0.2);
    EXPECT_NEAR(summary.efficiency_on_axis, result.after.efficiency_on_axis, 1e-12);
}

TEST(Tune, TheSameSeedGivesTheSameDesign) {
    const optics::Design design = bundled_design(3);
    TuneSpec spec = default_spec(design, 10.0, 0.0);
    spec.planes = {"meso-focus", "pattern-focal"};
    spec.starts = 2;
    spec.evaluations_per_start = 20;
    const TuneResult a = tune_design(design, spec);
    const TuneResult b = tune_design(design, spec);
    ASSERT_EQ(a.design.planes.size(), b.design.planes.size());
    for (std::size_t k = 0; k < a.design.planes.size(); ++k) EXPECT_EQ(a.design.planes[k].z, b.design.planes[k].z);
    EXPECT_EQ(a.evaluations, b.evaluations);
}

TEST(Tune, SaysWhenNoSpacingMeetsATarget) {
    const optics::Design design = optics::with_lenslet_count(bundled_design(1), 5, 5);
    TuneSpec spec = default_spec(design, 2.0, 0.0);
    spec.targets = {parse_target("efficiency_on_axis>=1.5")};
    spec.starts = 1;
    spec.evaluations_per_start = 10;
    const TuneResult result = tune_design(design, spec);
    EXPECT_FALSE(result.feasible);
    int violated = 0;
    for (const auto& c : result.conditions)
        if (c.slack < 0) {
            EXPECT_THAT(c.name, HasSubstr("efficiency_on_axis >= 1.5"));
            ++violated;
        }
    EXPECT_EQ(violated, 1);
}

TEST(Tune, TheTunedFileIsTheGivenOneWithNewSpacings) {
    const std::string path = std::string(RFD_SOURCE_DIR) + "/designs/design3.toml";
    const std::string text = read_text_file(path);
    const optics::Design design = optics::parse_design(text, path);
    TuneSpec spec = default_spec(design, 10.0, 0.0);
    spec.planes = {"meso-focus", "pattern-image", "pattern-focal"};
    spec.starts = 1;
    spec.evaluations_per_start = 50;
    const TuneResult result = tune_design(design, spec);
    const std::string tuned = tuned_design_text(text, design, result, "line one\n\nline three");
    EXPECT_EQ(tuned.rfind("# line one\n#\n# line three\n\n", 0), 0u);
    const optics::Design reread = optics::parse_design(tuned, "tuned.toml");
    for (std::size_t k = 0; k < reread.planes.size(); ++k)
        EXPECT_NEAR(reread.planes[k].z, result.design.planes[k].z, 1e-9) << reread.planes[k].name;
    // Every line of the given file is there, in order, but the z_mm lines that changed.
    std::size_t changed = 0, kept = 0, from = 0;
    for (std::size_t start = 0; start < text.size();) {
        const std::size_t end = text.find('\n', start);
        const std::string line = text.substr(start, end - start);
        start = end + 1;
        const std::size_t at = tuned.find(line + "\n", from);
        if (at == std::string::npos) {
            EXPECT_EQ(line.rfind("z_mm", 0), 0u) << line;
            ++changed;
        } else {
            from = at + line.size();
            ++kept;
        }
    }
    EXPECT_EQ(changed, 4u);  // B, C, D and E moved
    EXPECT_GT(kept, 50u);
}

TEST(Tune, RefusesWhatItCannotDo) {
    EXPECT_EQ(parse_target("field_of_view_deg>=25").value, 25.0);
    EXPECT_FALSE(parse_target("efficiency_mean<=0.5").at_least);
    EXPECT_THROW(parse_target("fov>=25"), InputError);
    EXPECT_THROW(parse_target("efficiency_on_axis>=most"), InputError);
    EXPECT_THROW(parse_target("efficiency_on_axis=0.5"), InputError);
    const optics::Design design = bundled_design(3);
    TuneSpec spec = default_spec(design, 10.0, 0.0);
    spec.free = {free_spacing(design, "A", 10.0, 0.0)};
    EXPECT_THROW(check_spec(design, spec), InputError);
    spec = default_spec(design, 10.0, 0.0);
    spec.planes = {"no-such-plane"};
    try {
        check_spec(design, spec);
        ADD_FAILURE() << "an unknown plane condition was accepted";
    } catch (const InputError& e) {
        EXPECT_THAT(e.what(), HasSubstr("meso-focus"));
    }
}

}  // namespace
}  // namespace rfd::tune
