// The lens-system file: every malformed prescription is an InputError naming the file, the
// line and the dotted key; the bundled lenses give their closed-form cardinal points.

#include <filesystem>
#include <functional>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "optics/lens_file.hpp"
#include "optics/paraxial.hpp"

namespace rfd::optics {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

// The message of the InputError that parsing `text` throws ("" if none is thrown).
std::string lens_error_of(const std::string& text) {
    try {
        parse_lens_system(text, "lens.toml");
    } catch (const InputError& error) {
        return error.what();
    }
    return "";
}

// Line 1 is the name, line 2 the first [[surface]]; the second surface is always valid.
std::string lens(const std::string& first_surface_keys) {
    return "name = \"test\"\n[[surface]]\n" + first_surface_keys +
           "[[surface]]\nradius = \"flat\"\nmaterial = \"air\"\nsemi_diameter_mm = 5\n";
}

TEST(LensFile, EachMistakeNamesFileLineAndKey) {
    EXPECT_THAT(lens_error_of(lens("radius_mm = 0\nthickness_mm = 2\nindex = 1.5\nsemi_diameter_mm = 5\n")),
                HasSubstr("lens.toml:3:13: surface[0].radius_mm: a radius of 0 is not a surface; "
                          "use radius = \"flat\""));
    EXPECT_THAT(lens_error_of(lens("radius_mm = 20\nthickness_mm = 2\nindex = 1.5\nmaterial = \"N-BK7\"\n"
                              "semi_diameter_mm = 5\n")),
                HasSubstr("lens.toml:5:9: surface[0].index: give exactly one of material = \"NAME\" "
                          "or index = N"));
    EXPECT_THAT(lens_error_of(lens("radius_mm = 20\nthickness_mm = 2\nsemi_diameter_mm = 5\n")),
                AllOf(HasSubstr("lens.toml:2:"), HasSubstr("surface[0]"), HasSubstr("give exactly one of")));
    EXPECT_THAT(lens_error_of(lens("radius_mm = 20\nthickness_mm = 2\nmaterial = \"BK7\"\nsemi_diameter_mm = 5\n")),
                HasSubstr("lens.toml:5:12: surface[0].material: unknown material 'BK7'; known: air, N-BK7, "
                          "B270, fused-silica, PMMA, polycarbonate, PET"));
    EXPECT_THAT(lens_error_of(lens("radius_mm = 4\nthickness_mm = 2\nindex = 1.5\nsemi_diameter_mm = 5\n")),
                HasSubstr("lens.toml:6:20: surface[0].semi_diameter_mm: the surface does not extend to "
                          "this semi-diameter"));
    EXPECT_THAT(lens_error_of(lens("radius_mm = 20\nthikness_mm = 2\nindex = 1.5\nsemi_diameter_mm = 5\n")),
                HasSubstr("lens.toml:4:15: surface[0].thikness_mm: unknown key (did you mean 'thickness_mm'?)"));
    EXPECT_THAT(lens_error_of(lens("radius = \"flat\"\nconic = -1\nthickness_mm = 2\nindex = 1.5\nsemi_diameter_mm = 5\n")),
                HasSubstr("lens.toml:4:9: surface[0].conic: a flat surface has no conic constant"));
    EXPECT_THAT(lens_error_of(lens("radius = 20\nthickness_mm = 2\nindex = 1.5\nsemi_diameter_mm = 5\n")),
                HasSubstr("surface[0].radius: expected a string, found an integer"));
    EXPECT_THAT(lens_error_of(lens("radius = \"convex\"\nthickness_mm = 2\nindex = 1.5\nsemi_diameter_mm = 5\n")),
                HasSubstr("surface[0].radius: expected radius = \"flat\" or a number in radius_mm"));
    EXPECT_THAT(lens_error_of(lens("radius_mm = 20\nthickness_mm = 2\nindex = 5\nsemi_diameter_mm = 5\n")),
                HasSubstr("surface[0].index: value 5 is outside the allowed range [1, 4]"));
    EXPECT_THAT(lens_error_of(lens("radius_mm = 20\nthickness_mm = -2\nindex = 1.5\nsemi_diameter_mm = 5\n")),
                HasSubstr("surface[0].thickness_mm: expected a number >= 0, found -2"));
    EXPECT_THAT(lens_error_of(lens("radius_mm = 20\nthickness_mm = 2\nindex = 1.5\nsemi_diameter_mm = 0\n")),
                HasSubstr("surface[0].semi_diameter_mm: expected a positive number, found 0"));
    EXPECT_THAT(lens_error_of(lens("radius_mm = 20\nthickness_cm = 0.2\nindex = 1.5\nsemi_diameter_mm = 5\n")),
                HasSubstr("lens.toml:4:16: surface[0].thickness_cm: wrong unit: expected 'thickness_mm' in "
                          "millimetres, found 'thickness_cm' (centimetres)"));
    EXPECT_THAT(lens_error_of("name = \"x\"\nfocal_length_mm = 50\n" + lens("radius_mm = 20\nthickness_mm = 2\n"
                                                                       "index = 1.5\nsemi_diameter_mm = 5\n")
                                                                     .substr(std::string("name = \"test\"\n").size())),
                HasSubstr("lens.toml:2:19: focal_length_mm: unknown key"));
    EXPECT_THAT(lens_error_of("name = \"x\"\n"), HasSubstr("missing required key 'surface'"));
    EXPECT_THAT(lens_error_of("name = \"x\"\n[[surface]]\nradius = \"flat\"\nindex = 1.5\n"),
                HasSubstr("a lens system needs at least two surfaces"));
    EXPECT_THROW(load_lens_system("/nonexistent/lens.toml"), IoError);
}

TEST(LensFile, TheLastSurfacesThicknessIsOptionalButChecked) {
    // Optional on the last surface (it places the image plane), so a wrong unit there can
    // only be caught when the table is finished: it must still say "wrong unit".
    const std::string text = "[[surface]]\nradius_mm = 20\nthickness_mm = 2\nindex = 1.5\nsemi_diameter_mm = 5\n"
                             "[[surface]]\nradius = \"flat\"\nmaterial = \"air\"\nsemi_diameter_mm = 5\n";
    EXPECT_EQ(parse_lens_system(text, "lens.toml").surfaces.size(), 2u);
    EXPECT_EQ(parse_lens_system(text + "thickness_mm = 30\n", "lens.toml").surfaces.size(), 3u);
    EXPECT_THAT(lens_error_of(text + "thickness_cm = 3\n"),
                HasSubstr("lens.toml:10:16: surface[1].thickness_cm: wrong unit: expected 'thickness_mm' in "
                          "millimetres, found 'thickness_cm' (centimetres)"));
    EXPECT_THAT(lens_error_of(text + "thicknes_mm = 30\n"),
                HasSubstr("surface[1].thicknes_mm: unknown key (did you mean 'thickness_mm'?)"));
}

TEST(LensFile, SurfacesThatCrossInsideTheApertureAreRejected) {
    // Spheres: a biconvex lens too thin for its sags crosses at the rim.
    EXPECT_THAT(lens_error_of("[[surface]]\nradius_mm = 10\nthickness_mm = 1\nindex = 1.5\nsemi_diameter_mm = 5\n"
                         "[[surface]]\nradius_mm = -10\nmaterial = \"air\"\nsemi_diameter_mm = 5\n"),
                AllOf(HasSubstr("lens.toml:3:16: surface[0].thickness_mm: surfaces S1 and S2 intersect "
                                "inside the aperture"),
                      HasSubstr("at radius 5.0")));
    // A strong hyperboloid (R = 2, k = -50) 0.03 mm in front of a sphere (R = 10): its sag
    // exceeds the sphere's between r ~ 0.6 and r ~ 2.5 mm (at r = 1: 0.108 against 0.050 mm)
    // and falls behind again toward the rim (at r = 5: 0.675 against 1.340 mm), so the two
    // surfaces cut through each other well inside the aperture, not at its edge.
    const std::string crossing =
        "[[surface]]\nradius_mm = 2.0\nconic = -50\nthickness_mm = 0.03\nindex = 1.5\nsemi_diameter_mm = 5\n"
        "[[surface]]\nradius_mm = 10\nmaterial = \"air\"\nsemi_diameter_mm = 5\n";
    const double rim_gap = 0.03 + sag(Conic{0.1}, 25.0).value() - sag(Conic{0.5, -50}, 25.0).value();
    const double mid_gap = 0.03 + sag(Conic{0.1}, 1.0).value() - sag(Conic{0.5, -50}, 1.0).value();
    ASSERT_GT(rim_gap, 0.5);   // apart at the rim ...
    ASSERT_LT(mid_gap, -0.02);  // ... crossed at r = 1 mm
    EXPECT_THAT(lens_error_of(crossing), AllOf(HasSubstr("lens.toml:4:16: surface[0].thickness_mm"),
                                          HasSubstr("intersect inside the aperture")));
    // With room to spare (0.1 mm more than the deepest crossing) the same pair is accepted.
    const std::string apart =
        "[[surface]]\nradius_mm = 2.0\nconic = -50\nthickness_mm = 0.13\nindex = 1.5\nsemi_diameter_mm = 5\n"
        "[[surface]]\nradius_mm = 10\nmaterial = \"air\"\nsemi_diameter_mm = 5\n";
    EXPECT_EQ(lens_error_of(apart), "");
}

std::filesystem::path lens_file(const char* name) {
    return std::filesystem::path(RFD_SOURCE_DIR) / "designs" / "lenses" / name;
}

TEST(LensFile, BundledLensesHaveTheirClosedFormFocalLengths) {
    // Edmund PCX, N-BK7 (n = 1.5168), R = 25.84, t = 5.3: f = R/(n-1) = 50.0000 mm exactly
    // (25.84 / 0.5168 = 50), BFL = f - t/n curved side first, BFL = f flat side first.
    const double n = 1.5168, t = 5.3, f = 25.84 / (n - 1);
    EXPECT_NEAR(f, 50.0, 1e-12);
    const auto curved = cardinal_points(load_lens_system(lens_file("edmund_pcx_25x50.toml")));
    EXPECT_NEAR(curved.efl, f, 1e-9);
    EXPECT_NEAR(curved.bfl, f - t / n, 1e-9);
    EXPECT_NEAR(curved.ffl, f, 1e-9);
    const SequentialSystem flat_first = load_lens_system(lens_file("edmund_pcx_25x50_flat_first.toml"));
    const auto flat = cardinal_points(flat_first);
    EXPECT_NEAR(flat.efl, f, 1e-9);
    EXPECT_NEAR(flat.bfl, f, 1e-9);
    EXPECT_NEAR(flat.ffl, f - t / n, 1e-9);
    // The turned-round file is the reversed curved-first one, shifted by t along z.
    const SequentialSystem turned = reversed(load_lens_system(lens_file("edmund_pcx_25x50.toml")));
    ASSERT_EQ(turned.surfaces.size(), flat_first.surfaces.size());
    for (std::size_t s = 0; s < turned.surfaces.size(); ++s) {
        EXPECT_NEAR(turned.surfaces[s].z + t, flat_first.surfaces[s].z, 1e-12);
        EXPECT_NEAR(curvature_of(turned.surfaces[s].profile), curvature_of(flat_first.surfaces[s].profile), 1e-15);
        EXPECT_EQ(turned.surfaces[s].index_after, flat_first.surfaces[s].index_after);
    }
    // Two B270 lenslets back to back (n = 1.523, R = 5.4915, t = 2 each): Gullstrand with
    // P1 = (n-1)/R and the principal planes 2t/n apart, P = 2 P1 - (2t/n) P1^2.
    const double nb = 1.523, rb = 5.4915, tb = 2.0, p1 = (nb - 1) / rb;
    const auto pair = cardinal_points(load_lens_system(lens_file("pcx_pair_back_to_back.toml")));
    EXPECT_NEAR(pair.power, 2 * p1 - (2 * tb / nb) * p1 * p1, 1e-15);
    EXPECT_NEAR(pair.efl, 1 / (2 * p1 - (2 * tb / nb) * p1 * p1), 1e-9);
    // Thick for their focal length: 0.57 of one lenslet's, not a half.
    EXPECT_NEAR(pair.efl / (rb / (nb - 1)), 1 / (2 - (2 * tb / nb) * p1), 1e-12);
}

TEST(LensFile, BackFocalLengthIsFromTheLensNotTheImagePlane) {
    // A plano-convex lens, curved side first: f = R / (n - 1), and the rear focal point lies
    // f - t / n behind its flat back. A last thickness adds an image plane 40 mm behind the
    // lens; the lens and its back focal length stay the same.
    const double r = 25.84, t = 5.3, n = 1.5;
    const auto text = [&](const std::string& last_thickness) {
        return "name = \"pcx\"\n[[surface]]\nradius_mm = " + std::to_string(r) + "\nthickness_mm = " +
               std::to_string(t) + "\nindex = 1.5\nsemi_diameter_mm = 12.5\n[[surface]]\nradius = \"flat\"\n" +
               "material = \"air\"\nsemi_diameter_mm = 12.5\n" + last_thickness;
    };
    const SequentialSystem bare = parse_lens_system(text(""), "bare.toml");
    const SequentialSystem imaged = parse_lens_system(text("thickness_mm = 40\n"), "imaged.toml");
    ASSERT_EQ(imaged.surfaces.size(), 3u);
    EXPECT_EQ(last_lens_surface(bare), 1u);
    EXPECT_EQ(last_lens_surface(imaged), 1u);
    const double f = r / (n - 1), bfl = f - t / n;
    for (const SequentialSystem* system : {&bare, &imaged}) {
        const CardinalPoints points = cardinal_points(*system, 0, last_lens_surface(*system));
        EXPECT_NEAR(points.bfl, bfl, 1e-9);
        EXPECT_NEAR(points.last_vertex_z, t, 1e-12);
    }
}

}  // namespace
}  // namespace rfd::optics
