// Design files: the presets load with the thesis's numbers, and every kind of bad input
// is rejected with a message that names the file, line and key.

#include <cmath>
#include <fstream>
#include <iterator>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "optics/analysis.hpp"
#include "optics/design.hpp"

#include "tests/support/bundled.hpp"

namespace rfd::optics {
namespace {

using ::testing::HasSubstr;
using rfd::testing::bundled_design_path;

// A small valid Design I; tests break one thing at a time with replace().
const std::string kDesignI = R"([design]
name = "test"
kind = "I"

[printer]
dpi_x = 2880
dpi_y = 1440

[parts.array]
type = "lenslet_array"
lattice = "hexagonal"
pitch_mm = 2.358
count = [10, 10]
radius_mm = 1.4751
center_thickness_mm = 2.0
material = "PMMA"
focal_length_mm = 3.0

[parts.diffuser]
type = "sheet"
thickness_mm = 0.13
material = "PET"

[planes.A]
z_mm = 0.0
part = "array"
curved_side = "light"

[planes.B]
z_mm = 3.6592
pattern = true

[planes.C]
z_mm = 6.0
part = "diffuser"
diffuser = true
)";

std::string replace(std::string text, const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return text;
}

// Parses `text` and returns the InputError message ("" if it parsed).
std::string design_error_of(const std::string& text) {
    try {
        parse_design(text, "test.toml");
    } catch (const InputError& error) {
        return error.what();
    }
    return "";
}

TEST(Design, PresetsLoadWithTheThesisParts) {
    const Design one = load_design(bundled_design_path(1));
    EXPECT_EQ(one.kind, DesignKind::I);
    const auto& array = std::get<LensletArrayPart>(*one.plane("A").part);
    // 20.77 lenses per cm^2 on a hexagonal lattice: pitch^2 * sqrt(3)/2 = 100/20.77 mm^2.
    EXPECT_NEAR(array.lattice.pitch_x(), std::sqrt(100.0 / 20.77 / (std::sqrt(3.0) / 2)), 1e-12);
    EXPECT_NEAR(array.lattice.pitch_x(), 2.358, 5e-4);
    EXPECT_NEAR(focal_length(array.lens), 3.0, 1e-3);
    EXPECT_EQ(one.printer.dpi_x.value, 2880);
    EXPECT_EQ(one.printer.dpi_y.value, 1440);

    const Design two = load_design(bundled_design_path(2));
    const auto& glass = std::get<LensletArrayPart>(*two.plane("A").part);
    EXPECT_EQ(glass.lattice.count_x() * glass.lattice.count_y(), 30);
    EXPECT_NEAR(glass.lattice.count_x() * glass.lattice.pitch_x(), 24.0, 1e-12);
    EXPECT_NEAR(glass.lattice.count_y() * glass.lattice.pitch_y(), 24.0, 1e-12);
    EXPECT_EQ(two.plane("B").arrangement, Arrangement::BackToBack);

    const Design three = load_design(bundled_design_path(3));
    EXPECT_NEAR(focal_length(std::get<LensPart>(*three.plane("A").part).lens), 50.0, 0.01);
    EXPECT_EQ(std::get<LensPart>(*three.plane("B").part).diameter, 30.0);

    const Design four = load_design(bundled_design_path(4));
    ASSERT_TRUE(four.macro.has_value());
    EXPECT_EQ(four.macro->count_x, 7);
    EXPECT_EQ(four.macro->count_y, 7);
}

TEST(Design, PresetPlanesSitWhereTheOpticsWantThem) {
    // Design I and II: the pattern is in the back focal plane of A; Design II's diffuser is
    // the image of A through B (thesis 8.2.3).
    for (int n : {1, 2, 3}) {
        const DesignOptics optics(load_design(bundled_design_path(n)));
        const DesignSummary summary = summarise(optics);
        EXPECT_LT(std::abs(summary.focus_error_mm), 1e-3) << "design " << n;
        ASSERT_FALSE(summary.conjugates.empty());
        EXPECT_NEAR(summary.conjugates[0].plane_z, summary.conjugates[0].target_z, 1e-3);
        if (n == 2) {
            EXPECT_NEAR(summary.conjugates[1].plane_z, summary.conjugates[1].target_z, 1e-3);
        }
    }
}

TEST(Design, ValidTestDesignParses) { EXPECT_EQ(design_error_of(kDesignI), ""); }

TEST(Design, UnknownKeyNamesFileLineAndKey) {
    const std::string text = replace(kDesignI, "focal_length_mm = 3.0", "focal_length_mm = 3.0\nfocal_lenght_mm = 3.0");
    EXPECT_THAT(design_error_of(text), HasSubstr("test.toml:18"));
    EXPECT_THAT(design_error_of(text), HasSubstr("parts.array.focal_lenght_mm: unknown key"));
}

TEST(Design, MissingKeyNamesItsTable) {
    const std::string text = replace(kDesignI, "center_thickness_mm = 2.0\n", "");
    EXPECT_THAT(design_error_of(text), HasSubstr("missing required key 'parts.array.center_thickness_mm'"));
}

TEST(Design, WrongUnitIsSaidToBeAUnit) {
    const std::string text = replace(kDesignI, "z_mm = 6.0", "z_cm = 0.6");
    EXPECT_THAT(design_error_of(text), HasSubstr("wrong unit"));
    EXPECT_THAT(design_error_of(text), HasSubstr("planes.C.z_cm"));
}

TEST(Design, CellCornersOutsideTheLensSphereAreImpossible) {
    // Hex corner distance pitch/sqrt(3) = 1.361 mm > R = 1.2 mm.
    std::string text = replace(kDesignI, "radius_mm = 1.4751", "radius_mm = 1.2");
    text = replace(text, "focal_length_mm = 3.0", "focal_length_mm = 2.44");
    EXPECT_THAT(design_error_of(text), HasSubstr("cell corners"));
    EXPECT_THAT(design_error_of(text), HasSubstr("outside the lens sphere"));
    EXPECT_THAT(design_error_of(text), HasSubstr("parts.array.radius_mm"));
}

TEST(Design, LensThinnerThanItsSagIsImpossible) {
    const std::string text = replace(kDesignI, "center_thickness_mm = 2.0", "center_thickness_mm = 0.5");
    EXPECT_THAT(design_error_of(text), HasSubstr("thinner than its sag"));
}

TEST(Design, OverlappingPlanesAreRejected) {
    const std::string text = replace(kDesignI, "z_mm = 3.6592", "z_mm = 1.5");
    EXPECT_THAT(design_error_of(text), HasSubstr("plane B overlaps plane A by 0.5 mm"));
}

TEST(Design, PlanesTouchingWithinRoundingBuildASystemInOrder) {
    // Found by fuzz/fuzz_design.cpp: B starts 5e-7 mm before A ends, which the overlap
    // check takes for touching; build_system then put B's surface before A's back and
    // failed its ordering check (an abort) instead of placing B on A.
    const std::string text = replace(kDesignI, "z_mm = 3.6592", "z_mm = 1.9999995");
    ASSERT_EQ(design_error_of(text), "");
    const SequentialSystem system = build_system(parse_design(text, "test.toml"));
    ASSERT_EQ(system.surfaces[2].label, "B pattern");
    EXPECT_EQ(system.surfaces[2].z, system.surfaces[1].z);
    EXPECT_EQ(system.surfaces[1].z, 2.0);
}

TEST(Design, NegativeDistancesAreRejected) {
    const std::string text = replace(kDesignI, "z_mm = 6.0", "z_mm = 3.0");
    EXPECT_THAT(design_error_of(text), HasSubstr("negative or zero distance from plane B"));
    EXPECT_THAT(design_error_of(text), HasSubstr("planes.C.z_mm"));
}

TEST(Design, NegativeThicknessIsRejected) {
    const std::string text = replace(kDesignI, "thickness_mm = 0.13", "thickness_mm = -0.13");
    EXPECT_THAT(design_error_of(text), HasSubstr("parts.diffuser.thickness_mm"));
    EXPECT_THAT(design_error_of(text), HasSubstr("outside the allowed range [0.001, 100000]"));
}

// Values no part has, which would make every derived figure 0, huge or NaN, are refused
// with their key (rfd design show printed "pitch 0.0000 mm" and "nan um" for 3e38).
TEST(Design, LengthsAndDensitiesOutsideWhatPartsHaveAreRejected) {
    const std::string dense = replace(kDesignI, "pitch_mm = 2.358", "lenses_per_cm2 = 3e38");
    EXPECT_THAT(design_error_of(dense), AllOf(HasSubstr("parts.array.lenses_per_cm2"), HasSubstr("outside the allowed range")));
    EXPECT_EQ(design_error_of(replace(kDesignI, "pitch_mm = 2.358", "lenses_per_cm2 = 20.77")), "");
    EXPECT_THAT(design_error_of(replace(kDesignI, "pitch_mm = 2.358", "pitch_mm = 1e-9")),
                AllOf(HasSubstr("parts.array.pitch_mm"), HasSubstr("outside the allowed range")));
    EXPECT_THAT(design_error_of(replace(kDesignI, "radius_mm = 1.4751", "radius_mm = 1e300")),
                HasSubstr("parts.array.radius_mm"));
    const std::string rectangular = replace(replace(kDesignI, "lattice = \"hexagonal\"", "lattice = \"rectangular\""),
                                            "pitch_mm = 2.358", "pitch_mm = [2.358, 1e7]");
    EXPECT_THAT(design_error_of(rectangular), AllOf(HasSubstr("parts.array.pitch_mm"), HasSubstr("expected lengths from")));
}

TEST(Design, FocalLengthMustMatchThePrescription) {
    const std::string text = replace(kDesignI, "focal_length_mm = 3.0", "focal_length_mm = 4.0");
    EXPECT_THAT(design_error_of(text), HasSubstr("give f = R/(n-1) = 3"));
}

TEST(Design, ExactlyOnePatternPlaneAndADiffuserForDesignI) {
    EXPECT_THAT(design_error_of(replace(kDesignI, "pattern = true", "pattern = false\npart = \"diffuser\"")),
                HasSubstr("exactly one plane with pattern = true"));
    EXPECT_THAT(design_error_of(replace(kDesignI, "diffuser = true", "diffuser = false")),
                HasSubstr("diffuser"));
}

TEST(Design, UnknownPartAndMaterialAreNamed) {
    EXPECT_THAT(design_error_of(replace(kDesignI, "part = \"array\"", "part = \"arrray\"")),
                HasSubstr("no part named 'arrray'"));
    EXPECT_THAT(design_error_of(replace(kDesignI, "material = \"PMMA\"", "material = \"unobtainium\"")),
                HasSubstr("unknown material 'unobtainium'"));
}

TEST(Design, MacroGridOnlyForDesignIVAndItMustFitThePart) {
    EXPECT_THAT(design_error_of(kDesignI + "\n[macro]\ncount = [2, 2]\npitch_mm = [30.0, 30.0]\n"),
                HasSubstr("Design IV only"));
    std::ifstream file(std::string(RFD_SOURCE_DIR) + "/designs/design4.toml");
    const std::string four((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    EXPECT_EQ(design_error_of(four), "");
    EXPECT_THAT(design_error_of(replace(four, "pitch_mm = [34.0, 34.0]", "pitch_mm = [20.0, 34.0]")),
                HasSubstr("smaller than the widest part (30 x 30 mm)"));
}

TEST(Design, BuildSystemPlacesSurfacesAsDocumented) {
    const Design design = parse_design(kDesignI, "test.toml");
    const SequentialSystem system = build_system(design);
    ASSERT_EQ(system.surfaces.size(), 5u);  // A front, A back, B pattern, C diffuser, C back
    EXPECT_EQ(system.surfaces[0].label, "A front");
    EXPECT_DOUBLE_EQ(curvature_of(system.surfaces[0].profile), 1.0 / 1.4751);
    EXPECT_DOUBLE_EQ(system.surfaces[1].z, 2.0);
    EXPECT_EQ(system.surfaces[2].label, "B pattern");
    EXPECT_TRUE(std::holds_alternative<LatticeAperture>(system.surfaces[2].aperture));
    EXPECT_EQ(system.surfaces[3].label, "C diffuser");
}

}  // namespace
}  // namespace rfd::optics
