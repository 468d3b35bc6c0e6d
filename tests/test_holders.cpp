// The lens holders (holders/): expressions and closed-form volumes against hand
// computation; for every preset design the generated OpenSCAD built by openscad, with
// every check of the built STLs asserted (solid, one piece, volume and box as designed,
// seats at their planes, no ray of the field of view touching the holder); checks that
// fail when the holder is wrong; broken designs rejected before OpenSCAD runs.

#include <array>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/command.hpp"
#include "core/error.hpp"
#include "holders/mesh_check.hpp"
#include "holders/checks.hpp"
#include "holders/beam.hpp"
#include "holders/coupon.hpp"
#include "holders/expr.hpp"
#include "holders/generate.hpp"
#include "holders/openscad.hpp"
#include "holders/profile.hpp"
#include "optics/design.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/bundled.hpp"

namespace rfd::holders {
namespace {

using ::testing::HasSubstr;
using rfd::testing::bundled_design_path;

// The film of the default printer (the Epson: two sheets back to back).
const PatternFilm kFilm{0.1, 2};

std::string read_text(const std::string& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

// The preset's text with one line replaced (the design keeps its file name for messages).
optics::Design edited_preset(int n, const std::string& from, const std::string& to) {
    std::string text = read_text(bundled_design_path(n));
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
    return optics::parse_design(text, bundled_design_path(n));
}

TEST(HolderExpr, CarriesTextAndValueWithTheRightBrackets) {
    ScadParameters p;
    const Expr a = p.define("a", 2.0), b = p.define("b", 3.0), c = p.define("c", 5.0);
    const Expr e = (a + b) * c - (a - b);
    EXPECT_EQ(e.text, "(a + b) * c - (a - b)");
    EXPECT_DOUBLE_EQ(e.value, 26.0);
    const Expr f = a / (b * c);
    EXPECT_EQ(f.text, "a / (b * c)");
    EXPECT_DOUBLE_EQ(f.value, 2.0 / 15.0);
    EXPECT_EQ(scad_number(0.1 + 0.2), "0.3");
    EXPECT_EQ(scad_number(-0.0), "0");
    EXPECT_EQ(scad_number(47.01540000001), "47.0154");
}

TEST(HolderFacets, CircumscribedCornersStayWithinTheTolerance) {
    for (const double d : {2.0, 25.0, 30.4, 150.0})
        for (const double tolerance : {0.005, 0.01, 0.05}) {
            const int n = circle_facets(d, tolerance);
            EXPECT_EQ(n % 4, 0);
            EXPECT_GE(n, 32);
            const double corner_out = d / 2 * (1 / std::cos(std::numbers::pi / n) - 1);
            EXPECT_LE(corner_out, tolerance * (1 + 1e-12)) << d << " " << tolerance;
        }
}

// A prism, a frustum and a cylinder, end to end, plus notches crossing the prism: the
// cavity volume against the volumes written out by hand.
TEST(HolderVolume, SectionsMatchHandComputedSolids) {
    Holder h;
    Section box;
    box.kind = Section::Kind::Rect;
    box.z0 = 0, box.z1 = 2;
    box.width = box.width1 = 10, box.height = box.height1 = 6;
    Section frustum = box;
    frustum.z0 = 2, frustum.z1 = 5;
    frustum.width1 = 16, frustum.height1 = 12;
    Section cylinder;
    cylinder.kind = Section::Kind::Circle;
    cylinder.z0 = 5, cylinder.z1 = 9;
    cylinder.width = cylinder.width1 = 8;
    cylinder.facets = 40;
    Section notches;
    notches.kind = Section::Kind::Rect;
    notches.z0 = 0, notches.z1 = 2;
    notches.width = notches.width1 = 0, notches.height = notches.height1 = 0;
    notches.notches = CornerNotches{5, 3, 2};  // squares [4, 6] x [2, 4]: a quarter inside the prism
    h.sections = {box, frustum, cylinder, notches};
    const double prism_volume = 10 * 6 * 2;
    // Frustum of a rectangle: integral of (w0 + t dw)(h0 + t dh) over its length.
    const double frustum_volume = 3 * (10 * 6 + (10 * 6 + 6 * 6) / 2.0 + 6 * 6 / 3.0);
    const double cylinder_volume = 40 * 4.0 * 4.0 * std::tan(std::numbers::pi / 40) * 4;
    const double notch_volume = 4 * (4 - 1) * 2;
    EXPECT_NEAR(h.cavity_volume(), prism_volume + frustum_volume + cylinder_volume + notch_volume, 1e-6);
}

TEST(HolderProfile, ReadsKeysAndRejectsUnknownOrUnprintableOnes) {
    const HolderProfile p = parse_profile("[printer]\nclearance_mm = 0.15\n[holder]\nseat_mm = 1.0\n", "fdm.toml");
    EXPECT_DOUBLE_EQ(p.clearance, 0.15);
    EXPECT_DOUBLE_EQ(p.seat, 1.0);
    EXPECT_DOUBLE_EQ(p.min_wall, HolderProfile{}.min_wall);
    try {
        parse_profile("[printer]\nclearence_mm = 0.15\n", "fdm.toml");
        FAIL() << "a misspelt key was accepted";
    } catch (const InputError& e) {
        EXPECT_THAT(e.what(), HasSubstr("fdm.toml:2"));
        EXPECT_THAT(e.what(), HasSubstr("clearence_mm"));
    }
    EXPECT_THROW(parse_profile("[printer]\nclearance_mm = -0.1\n", "fdm.toml"), InputError);
    // The printed film is the film printer's: a 3D printer profile that sets it is told where it went.
    EXPECT_THAT(testing::error_of([] { parse_profile("[holder]\nfilm_mm = 0.1\n", "fdm.toml"); }),
                HasSubstr("fdm.toml:2:11: holder.film_mm: the printed film is the film printer's: set film_mm and "
                          "sheets in its profile"));
    EXPECT_THAT(testing::error_of([] { parse_profile("[holder]\npattern_sheets = 2\n", "fdm.toml"); }),
                HasSubstr("holder.pattern_sheets: the printed film is the film printer's"));
    EXPECT_THROW(parse_profile("[printer]\nnozzle_mm = 0.4\n[holder]\nbaffle_mm = 0.2\n", "fdm.toml"), InputError);
}

// Builds every printed part of `holder` into `dir` and checks them.
HolderCheck build_and_check(const Holder& holder, const optics::Design& design, const testing::TempDir& dir) {
    const auto scad = dir / "holder.scad";
    std::ofstream(scad) << to_scad(holder);
    std::vector<std::pair<PrintedPart, std::filesystem::path>> stls;
    for (const PrintedPart& part : holder.parts) {
        const auto stl = dir / ("holder_" + part.name + ".stl");
        build_stl(scad, part.name, stl, 600);
        stls.emplace_back(part, stl);
    }
    return check_holder(holder, design, stls);
}

TEST(HolderFilm, ThePatternPocketKeepsRoomForEverySheetOfFilm) {
    // Design I's pattern sheets rest in front of the pattern face: the pocket's front moves
    // forward by the thickness of the stack.
    const optics::Design design = optics::load_design(bundled_design_path(1));
    const auto pattern_pocket_front = [&](const PatternFilm& film) {
        const Holder holder = make_holder(design, HolderProfile{}, film);
        for (const auto& entry : holder.parameters.entries())
            if (entry.comment.rfind("the pattern sheets rest here", 0) == 0) return entry.definition.value;
        ADD_FAILURE() << "no pocket for the pattern sheets";
        return 0.0;
    };
    const double one_sheet = pattern_pocket_front({0.1, 1});
    EXPECT_NEAR(one_sheet - pattern_pocket_front({0.1, 2}), 0.1, 1e-12);
    EXPECT_NEAR(one_sheet - pattern_pocket_front({0.25, 2}), 2 * 0.25 - 0.1, 1e-12);
}

class PresetHolder : public ::testing::TestWithParam<int> {};

TEST_P(PresetHolder, BuildsAndPassesEveryCheck) {
    if (!find_openscad()) GTEST_SKIP() << "openscad is not installed";
    // Design IV's 7 x 7 block takes OpenSCAD about a minute; a 3 x 3 block has every kind
    // of plate (bottom, middle, top) and every seam between cells.
    const optics::Design design = GetParam() == 4 ? edited_preset(4, "count = [7, 7]\npitch_mm", "count = [3, 3]\npitch_mm")
                                                  : optics::load_design(bundled_design_path(GetParam()));
    const Holder holder = make_holder(design, HolderProfile{}, kFilm);
    const testing::TempDir dir;
    const HolderCheck check = build_and_check(holder, design, dir);
    EXPECT_THAT(check.problems(), ::testing::IsEmpty());
    ASSERT_EQ(check.parts.size(), holder.parts.size());
    for (const PartCheck& p : check.parts) {
        EXPECT_EQ(p.mesh.components, 1u) << p.name;
        EXPECT_TRUE(p.mesh.closed && p.mesh.bounds_volume && p.mesh.outward && !p.mesh.self_intersecting) << p.name;
        EXPECT_LT(std::abs(p.volume_error), 0.005) << p.name;
        EXPECT_LT(p.box_error, 0.02) << p.name;
    }
    // Every part of the design has a seat, found within 0.05 mm of its plane.
    std::size_t parts_of_design = 0;
    for (const auto& plane : design.planes) parts_of_design += plane.part.has_value();
    EXPECT_GE(check.seats.size(), design.kind == optics::DesignKind::I ? 2u : parts_of_design);
    for (const SeatCheck& s : check.seats) {
        ASSERT_TRUE(s.measured_z.has_value()) << s.plane;
        EXPECT_NEAR(*s.measured_z, s.expected_z, 0.05) << s.plane;
    }
    EXPECT_GT(check.clearance.rays, 500u);
    EXPECT_EQ(check.clearance.blocked, 0u);
    EXPECT_GT(check.clearance.min_clearance, 0.0);
}

INSTANTIATE_TEST_SUITE_P(Designs, PresetHolder, ::testing::Values(1, 2, 3, 4),
                         [](const auto& param_info) { return "Design" + std::to_string(param_info.param); });

TEST(HolderSeats, LieWhereThePartsFacesMustBe) {
    // Independent of the generator's own numbers: the faces from the design's prescription.
    const optics::Design design = optics::load_design(bundled_design_path(3));
    const Holder holder = make_holder(design, HolderProfile{}, kFilm);
    ASSERT_EQ(holder.seats.size(), 5u);
    EXPECT_NEAR(holder.seats[0].z, 0.0 + 5.3, 1e-9);  // main lens's flat back
    EXPECT_NEAR(holder.seats[1].z, 47.0154, 1e-9);    // field lens's flat front
    EXPECT_NEAR(holder.seats[2].z, 54.0154 + 2.0, 1e-9);  // meso array's flat back
    EXPECT_NEAR(holder.seats[4].z, 74.3334, 1e-9);    // projection array's flat front
    // The pair: the front array's outer lenslets, where their curved faces reach the seat
    // band: the vertex plane plus the sag at 2.0 - 0.8 mm from a lenslet's axis, in front
    // of the pattern by half the film stack between the flats.
    const double r = 5.4915, rho = 2.0 - 0.8, half_stack = kFilm.sheets * kFilm.thickness / 2;
    EXPECT_NEAR(holder.seats[3].z, 65.1466 - half_stack - 2.0 + (r - std::sqrt(r * r - rho * rho)), 1e-9);
}

TEST(HolderBeam, EnvelopeOverAnIntervalIsTheLargestAtAnyDepth) {
    // Two hand-made paths: one crossing the axis (its |x| is largest at the interval's ends,
    // smallest inside), one in a lenslet centred at x = 1.
    BeamPath crossing{{{-2, 0, 0}, {2, 1, 4}, {2, 3, 6}}, Eigen::Vector2d::Zero()};
    BeamPath offset{{{1.5, -0.5, 0}, {0.5, -0.5, 6}}, Eigen::Vector2d(1, 0)};
    const std::vector<BeamPath> paths{crossing, offset};
    const Envelope e = envelope_over(paths, 1.0, 5.0, false);
    EXPECT_DOUBLE_EQ(e.x, 2.0);   // crossing, from z = 4 on
    EXPECT_DOUBLE_EQ(e.y, 2.0);   // crossing at z = 5: halfway from 1 to 3
    EXPECT_DOUBLE_EQ(e.r, std::hypot(2.0, 2.0));
    const Envelope cell = envelope_over(paths, 1.0, 5.0, true);
    EXPECT_DOUBLE_EQ(cell.x, 2.0);  // the crossing path's cell is the origin's
    const Envelope only_offset = envelope_over({offset}, 0.0, 3.0, true);
    EXPECT_DOUBLE_EQ(only_offset.x, 0.5);  // 0.5 right of its centre at z = 0, on it at z = 3
    EXPECT_TRUE(envelope_over(paths, 7.0, 8.0, false).empty);

    // Design II's traced beam: never below the envelope at any depth inside, equal to the
    // largest of a fine sampling up to the sampling's own resolution.
    const optics::Design design = optics::load_design(bundled_design_path(2));
    const std::vector<BeamPath> beam = beam_paths(design, {}, -1.0, 30.0, BeamSampling{3, 4});
    ASSERT_FALSE(beam.empty());
    const double z0 = 0.0, z1 = 25.0;  // the lenslets to the diffuser
    const int steps = 5000;
    // A sampled maximum falls short by at most slope x step / 2; slopes here stay below 4.
    const double resolution = 2 * (z1 - z0) / steps;
    const Envelope exact = envelope_over(beam, z0, z1, true);
    Envelope sampled;
    for (int k = 0; k <= steps; ++k) {
        const Envelope at = envelope_at(beam, z0 + (z1 - z0) * k / steps, true);
        EXPECT_LE(at.x, exact.x + 1e-12);
        EXPECT_LE(at.y, exact.y + 1e-12);
        EXPECT_LE(at.r, exact.r + 1e-12);
        sampled.x = std::max(sampled.x, at.x), sampled.y = std::max(sampled.y, at.y), sampled.r = std::max(sampled.r, at.r);
    }
    EXPECT_NEAR(sampled.x, exact.x, resolution);
    EXPECT_NEAR(sampled.y, exact.y, resolution);
    EXPECT_NEAR(sampled.r, exact.r, resolution);
}

TEST(HolderChecks, FailWhenTheHolderIsWrong) {
    if (!find_openscad()) GTEST_SKIP() << "openscad is not installed";
    const optics::Design design = optics::load_design(bundled_design_path(2));
    Holder holder = make_holder(design, HolderProfile{}, kFilm);
    // Narrow the channel from the corrective pair to the diffuser: light must hit it.
    for (Section& s : holder.sections)
        if (s.module == "channel_B_C") {
            s.width = s.width - 3.0;
            s.width1 = s.width1 - 3.0;
        }
    // And claim a seat 0.1 mm from where it is built.
    holder.seats[0].z += 0.1;
    const testing::TempDir dir;
    const HolderCheck check = build_and_check(holder, design, dir);
    EXPECT_GT(check.clearance.blocked, 0u);
    const auto problems = check.problems();
    EXPECT_THAT(problems, ::testing::Contains(HasSubstr("beam clearance")));
    EXPECT_THAT(problems, ::testing::Contains(HasSubstr("seat of plane A")));
}

TEST(HolderDesigns, BrokenDesignsAreRejectedBeforeOpenScad) {
    // Cells closer than the field lens's pocket and its walls: no wall between the cells.
    try {
        make_holder(edited_preset(4, "pitch_mm = [34.0, 34.0]", "pitch_mm = [31.0, 31.0]"), HolderProfile{}, kFilm);
        FAIL() << "a 30 mm field lens in 31 mm cells was accepted";
    } catch (const InputError& e) {
        EXPECT_THAT(e.what(), HasSubstr("macro-pixel pitch"));
        EXPECT_THAT(e.what(), HasSubstr("design4.toml"));
    }
    // A diffuser whose pocket overlaps the corrective pair's, though the parts do not touch.
    try {
        make_holder(edited_preset(2, "z_mm = 25.1278", "z_mm = 13.8"), HolderProfile{}, kFilm);
        FAIL() << "overlapping pockets were accepted";
    } catch (const InputError& e) {
        EXPECT_THAT(e.what(), HasSubstr("overlaps the pocket of plane B"));
    }
    // Planes whose parts overlap are rejected when the design is read.
    EXPECT_THROW(edited_preset(2, "z_mm = 25.1278", "z_mm = 12.0"), InputError);
}

TEST(HolderDesigns, DesignTwoBafflesThinTowardThePattern) {
    const Holder holder = make_holder(optics::load_design(bundled_design_path(2)), HolderProfile{}, kFilm);
    std::vector<const Section*> baffles;
    for (const Section& s : holder.sections)
        if (s.kind == Section::Kind::Cells) baffles.push_back(&s);
    ASSERT_GE(baffles.size(), 2u);
    double previous = 1e9;
    for (const Section* s : baffles) {
        const double wall = s->cells.pitch_x() - s->width.value;
        EXPECT_LE(wall, previous + 1e-12);
        EXPECT_TRUE(wall == 0.0 || wall >= HolderProfile{}.nozzle) << wall;
        previous = wall;
    }
    // The first step is a real baffle, no thicker than the profile's baffle.
    const double first = baffles.front()->cells.pitch_x() - baffles.front()->width.value;
    EXPECT_GT(first, 0.0);
    EXPECT_LE(first, HolderProfile{}.baffle + 1e-12);
}

TEST(HolderScad, IsDeterministicAndParametric) {
    const optics::Design design = optics::load_design(bundled_design_path(1));
    const std::string a = to_scad(make_holder(design, HolderProfile{}, kFilm));
    const std::string b = to_scad(make_holder(design, HolderProfile{}, kFilm));
    EXPECT_EQ(a, b);
    EXPECT_THAT(a, HasSubstr("clearance = 0.2;"));
    EXPECT_THAT(a, HasSubstr("A_pocket_back = A_z + A_thickness;"));
    EXPECT_THAT(a, HasSubstr("module pocket_A()"));
    EXPECT_THAT(a, HasSubstr("module corner_sights()"));
}

TEST(HolderCoupon, BuildsToTheClosedFormVolume) {
    if (!find_openscad()) GTEST_SKIP() << "openscad is not installed";
    const Coupon coupon = make_coupon(25.0, 24.0, HolderProfile{});
    ASSERT_EQ(coupon.clearances.size(), 9u);
    EXPECT_DOUBLE_EQ(coupon.clearances.front(), 0.0);
    EXPECT_DOUBLE_EQ(coupon.clearances.back(), 0.4);
    const testing::TempDir dir;
    std::ofstream(dir / "coupon.scad") << coupon.scad;
    build_stl(dir / "coupon.scad", "coupon", dir / "coupon.stl");
    const MeshCheck mesh = check_stl(dir / "coupon.stl");
    EXPECT_THAT(mesh.problems(), ::testing::IsEmpty());
    EXPECT_NEAR(mesh.volume_mm3 / coupon.volume, 1.0, 1e-4);
    // The STL is binary: floats, good to 3e-5 mm at 300 mm.
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(mesh.min_mm[static_cast<std::size_t>(k)], coupon.box[0][k], 1e-4);
        EXPECT_NEAR(mesh.max_mm[static_cast<std::size_t>(k)], coupon.box[1][k], 1e-4);
    }
}

TEST(HolderOpenScad, ReportsErrorsAndLeavesNothingBehind) {
    if (!find_openscad()) GTEST_SKIP() << "openscad is not installed";
    const testing::TempDir dir;
    std::ofstream(dir / "bad.scad") << "part = \"x\";\ncube(undefined_size);\n";
    try {
        build_stl(dir / "bad.scad", "x", dir / "bad.stl");
        FAIL() << "a warning was accepted";
    } catch (const ToolError& e) {
        EXPECT_THAT(e.what(), HasSubstr("openscad failed"));
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "bad.stl"));
    for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
        EXPECT_EQ(entry.path().extension(), ".scad") << entry.path();
}

// A plate wider than 100 mm with frustum holes cut through its edge: OpenSCAD writes six
// significant digits, and the thin triangles it fans over the plate's faces fold over
// one another. build_stl collapses the slivers into a solid that passes every check.
TEST(HolderOpenScad, RemovesTheSliversOfWidePartsKeepingTheirShape) {
    if (!find_openscad()) GTEST_SKIP() << "openscad is not installed";
    const testing::TempDir dir;
    const int facets = 80, holes = 7;
    const double r = 12, scale = 0.9, cut_height = 10.02, below = 0.01;
    std::ofstream(dir / "plate.scad")
        << "part = \"plate\";\ndifference() {\n    translate([-120, -15, 0]) cube([240, 30, 10]);\n"
        << "    for (i = [0 : " << holes - 1 << "]) translate([-102 + 34 * i, -15, " << -below << "])\n"
        << "        linear_extrude(height = " << cut_height << ", scale = " << scale << ") circle(d = " << 2 * r
        << " / cos(180 / " << facets << "), $fn = " << facets << ");\n}\n";
    const CommandResult raw = run_command(shell_quoted(find_openscad()->string()) + " -o " +
                                          shell_quoted((dir / "raw.stl").string()) + " " +
                                          shell_quoted((dir / "plate.scad").string()));
    ASSERT_EQ(raw.exit_code, 0) << raw.output;
    EXPECT_TRUE(check_stl(dir / "raw.stl").self_intersecting) << "OpenSCAD's output no longer folds: the test shows nothing";

    const StlBuild build = build_stl(dir / "plate.scad", "plate", dir / "plate.stl");
    EXPECT_GT(build.slivers, 0u);
    const MeshCheck mesh = check_stl(dir / "plate.stl");
    EXPECT_THAT(mesh.problems(), ::testing::IsEmpty());
    // Half of each hole lies in the plate. A hole's area is the circumscribed polygon's,
    // shrinking linearly in scale with height: quadratic in z, so Simpson's rule is exact.
    const auto area = [&](double z) {
        const double s = 1 + (scale - 1) * (z + below) / cut_height;
        return facets * std::pow(r * s, 2) * std::tan(std::numbers::pi / facets);
    };
    const double hole = 10.0 / 6 * (area(0) + 4 * area(5) + area(10));
    // To the STL's rounding (six digits, 0.001 mm here); moving faces would show far more.
    EXPECT_NEAR(mesh.volume_mm3 / (240 * 30 * 10 - holes * hole / 2), 1.0, 1e-5);
}

// The clean-up must not mend what the checks are there to report.
TEST(HolderMesh, SliverRemovalLeavesABrokenMeshForTheChecks) {
    const testing::TempDir dir;
    // A tetrahedron with one face turned inside out.
    const std::array<std::array<const char*, 3>, 4> faces{{{"0 0 0", "0 1 0", "1 0 0"},
                                                           {"0 0 0", "1 0 0", "0 0 1"},
                                                           {"0 0 0", "0 0 1", "0 1 0"},
                                                           {"1 0 0", "0 0 1", "0 1 0"}}};
    std::string text = "solid t\n";
    for (const auto& f : faces)
        text += std::string("facet normal 0 0 0\nouter loop\nvertex ") + f[0] + "\nvertex " + f[1] + "\nvertex " +
                f[2] + "\nendloop\nendfacet\n";
    text += "endsolid t\n";
    std::ofstream(dir / "t.stl") << text;
    EXPECT_EQ(remove_slivers(dir / "t.stl"), 0u);
    EXPECT_EQ(read_text((dir / "t.stl").string()), text);
    EXPECT_FALSE(check_stl(dir / "t.stl").manifold);
}

}  // namespace
}  // namespace rfd::holders
