// print/: printer profiles, the tone mapping's inversion and two-sheet product, sheets read
// back (resolution tags, markers found where the design puts the corner lenslets, the
// mirror, determinism), PDF page size and tiling, the moire sheet, and bad input.

#include <cstdlib>
#include <cmath>
#include <random>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "optics/analysis.hpp"
#include "optics/design.hpp"
#include "patterns/raster.hpp"
#include "print/moire.hpp"
#include "print/layout.hpp"
#include "print/printed.hpp"
#include "print/printer.hpp"
#include "print/sheet.hpp"
#include "print/wedge.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/bundled.hpp"

namespace rfd::print {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using rfd::testing::bundled_design;
using ::testing::MatchesRegex;
using rfd::testing::error_of;
using rfd::testing::TempDir;


// A small test printer: non-square dots, a paper just big enough for Design II and its marks.
std::string small_printer_toml(double dpi_x, double dpi_y, double paper_w = 50, double paper_h = 60) {
    std::ostringstream s;
    s << "[printer]\nname = \"test printer\"\ndpi_x = " << dpi_x << "\ndpi_y = " << dpi_y
      << "\ngamma = 2.2\nmax_density = 2.0\nblack_level = 0.012\nsheets = 2\n"
      << "[paper]\nname = \"test\"\nwidth_mm = " << paper_w << "\nheight_mm = " << paper_h << "\nmargin_mm = 1\n";
    return s.str();
}

class Uniform final : public patterns::PatternSource {
public:
    Uniform(patterns::PatternGeometry g, float value) : g_(g), value_(value) {}
    const patterns::PatternGeometry& geometry() const override { return g_; }
    int channels() const override { return 1; }
    void render_row(int, std::span<float> out) const override { std::fill(out.begin(), out.end(), value_); }

private:
    patterns::PatternGeometry g_;
    float value_;
};

struct Page {
    int width = 0, height = 0;
    ImageFileSpec spec;
    std::vector<std::uint8_t> pixels;  // RGB
    int code(int x, int y, int c = 0) const {
        return pixels[(static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)) * 3 +
                      static_cast<std::size_t>(c)];
    }
};

Page read_page(const std::filesystem::path& path) {
    ImageFileReader in(path);
    Page page;
    page.spec = in.spec();
    page.width = page.spec.width;
    page.height = page.spec.height;
    page.pixels.resize(static_cast<std::size_t>(page.width) * static_cast<std::size_t>(page.height) * 3);
    in.read_rows(0, page.height, page.pixels);
    return page;
}

std::string read_bytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Writes a uniform pattern of `value` for `design` at the printer's dpi.
std::filesystem::path write_test_pattern(const TempDir& dir, const optics::Design& design,
                                         const PrinterProfile& printer, float value,
                                         const patterns::PatternAttributes& attributes = {{"white", "0.8"}}) {
    const auto g = patterns::pattern_geometry(design, printer.dpi_x, printer.dpi_y);
    const auto path = dir / "pattern.exr";
    patterns::write_pattern(path, Uniform(g, value), attributes);
    return path;
}


// ------------------------------------------------------------------ printed transparency

// Every dot a different value, exact in half floats: k / 16 plus 1/8 per channel.
class Steps final : public patterns::PatternSource {
public:
    explicit Steps(patterns::PatternGeometry g) : g_(g) {}
    const patterns::PatternGeometry& geometry() const override { return g_; }
    int channels() const override { return 3; }
    void render_row(int py, std::span<float> out) const override {
        for (int px = 0; px < g_.width; ++px)
            for (int c = 0; c < 3; ++c) out[static_cast<std::size_t>(px * 3 + c)] = value(px, py, c);
    }
    static float value(int px, int py, int c) { return static_cast<float>((px + 3 * py) % 17) / 16.0f + 0.125f * static_cast<float>(c); }

private:
    patterns::PatternGeometry g_;
};

TEST(PrintedTransparency, EachPointSeesItsDotAsPrinted) {
    const TempDir dir;
    const optics::Design design = bundled_design(2);
    const PrinterProfile printer = parse_printer(small_printer_toml(300, 150), "test.toml");
    const auto g = patterns::pattern_geometry(design, printer.dpi_x, printer.dpi_y);
    patterns::write_pattern(dir / "steps.exr", Steps(g), {{"white", "0.8"}});
    const PrintedTransparency printed(design, printer, dir / "steps.exr", 1.3, 2);
    EXPECT_EQ(printed.tone().white, 0.8);
    EXPECT_EQ(printed.tone().sheets, 2);

    std::mt19937_64 random(3);
    std::uniform_real_distribution<double> unit(-0.6, 0.6);  // a little past the sheet too
    std::vector<Eigen::Vector2d> points;
    for (int k = 0; k < 5000; ++k) points.emplace_back(unit(random) * g.size_mm().x(), unit(random) * g.size_mm().y());
    std::vector<float> out(points.size() * 3);
    printed.sample(points, out);
    int on_sheet = 0;
    for (std::size_t k = 0; k < points.size(); ++k) {
        const Eigen::Vector2d r = g.raster_position(points[k]);
        const int px = static_cast<int>(std::floor(r.x() + 0.5)), py = static_cast<int>(std::floor(r.y() + 0.5));
        const bool inside = px >= 0 && py >= 0 && px < g.width && py < g.height;
        on_sheet += inside;
        for (int c = 0; c < 3; ++c) {
            const double expected = inside ? printed.tone().stack_transmittance(Steps::value(px, py, c)) : 0.0;
            ASSERT_NEAR(out[k * 3 + static_cast<std::size_t>(c)], expected, 1e-6) << k;
        }
    }
    EXPECT_GT(on_sheet, 2500);
    EXPECT_LT(on_sheet, 4900);
}

// The sheet as printed, against the page rfd print sheet writes (cairo's drawing of the
// markers): in each corner lenslet's cell a dot is ink where the page inks it and clear where
// the page leaves it bare (dots within most of a dot of a line's edge, where the drawing is
// anti-aliased, not compared); elsewhere the pattern's own value.
TEST(MarkedTransparency, AgreesWithTheMarkersThePageInks) {
    TempDir dir;
    const optics::Design design = bundled_design(2);
    const PrinterProfile printer = parse_printer(small_printer_toml(1200, 600), "test.toml");
    const auto pattern_file = write_test_pattern(dir, design, printer, 0.4f);
    const SheetReport report = write_sheet(dir / "sheet.tif", design, printer, pattern_file, SheetOptions{});
    const Page page = read_page(dir / "sheet.tif");
    const PrintedTransparency printed(design, printer, pattern_file, 1.0, 1);
    const MarkedTransparency sheet(printed, design, printed.tone());
    const std::vector<MarkerShape> markers = marker_shapes(design, printer.dpi_x.dot_mm(), printer.dpi_y.dot_mm());
    ASSERT_EQ(markers.size(), 4u);
    const auto g = patterns::pattern_geometry(design, printer.dpi_x, printer.dpi_y);
    const int offset_x = report.layout.offset_x, offset_y = report.layout.offset_y;
    const float ink = static_cast<float>(printer.ink_transmittance());
    int compared = 0, inked = 0, disagree = 0;
    std::vector<Eigen::Vector2d> points;
    std::vector<bool> page_ink;
    for (const MarkerShape& m : markers) {
        const Eigen::Vector2d page_centre = report.layout.page_mm(m.centre);
        ASSERT_TRUE(std::any_of(report.layout.markers.begin(), report.layout.markers.end(), [&](const Marker& drawn) {
            return (drawn.centre - page_centre).norm() < 1e-9 && drawn.radius == m.radius && drawn.arm == m.arm;
        }));
        const Eigen::Vector2d dot = report.layout.page_dot(m.centre);
        const int reach_x = static_cast<int>(m.arm / printer.dpi_x.dot_mm()) + 2;
        const int reach_y = static_cast<int>(m.arm / printer.dpi_y.dot_mm()) + 2;
        const double margin = 0.75 * std::max(printer.dpi_x.dot_mm(), printer.dpi_y.dot_mm());
        for (int y = static_cast<int>(dot.y()) - reach_y; y <= static_cast<int>(dot.y()) + reach_y; ++y)
            for (int x = static_cast<int>(dot.x()) - reach_x; x <= static_cast<int>(dot.x()) + reach_x; ++x) {
                const Eigen::Vector2d mm = g.dot_centre(x - offset_x, y - offset_y);
                if ((mm - m.centre).norm() > 0.95 * m.arm) continue;
                // Away from every line's edge by most of a dot.
                const Eigen::Vector2d d = mm - m.centre;
                const double w = m.line_width, edge = std::min({std::abs(std::abs(d.norm() - m.radius) - 0.5 * w),
                                                                std::abs(std::abs(d.x()) - 0.5 * w),
                                                                std::abs(std::abs(d.y()) - 0.5 * w)});
                if (edge < margin) continue;
                points.push_back(mm);
                page_ink.push_back(page.code(x, y) < 128);
            }
    }
    // One call: the pattern file is read once.
    const auto channels = static_cast<std::size_t>(sheet.channels());
    std::vector<float> out(points.size() * channels);
    sheet.sample(points, out);
    for (std::size_t k = 0; k < points.size(); ++k) {
        const bool model_ink = out[k * channels] == ink;
        if (!model_ink) {
            EXPECT_EQ(out[k * channels], 1.0f);
        }
        disagree += page_ink[k] != model_ink;
        inked += model_ink;
        ++compared;
    }
    EXPECT_GT(compared, 1000);
    EXPECT_GT(inked, 100);
    EXPECT_EQ(disagree, 0);
    // Away from the marker cells: the pattern as printed.
    const Eigen::Vector2d middle = optics::DesignOptics(design).lattice().center({2, 2});
    std::vector<float> marked(static_cast<std::size_t>(sheet.channels())), plain(marked.size());
    sheet.sample(std::span<const Eigen::Vector2d>(&middle, 1), marked);
    printed.sample(std::span<const Eigen::Vector2d>(&middle, 1), plain);
    EXPECT_EQ(marked, plain);
}

TEST(PrintedTransparency, APatternForAnotherResolutionIsRefused) {
    const TempDir dir;
    const optics::Design design = bundled_design(2);
    const PrinterProfile printer = parse_printer(small_printer_toml(300, 150), "test.toml");
    const auto path = write_test_pattern(dir, design, parse_printer(small_printer_toml(200, 200), "other.toml"), 0.5f);
    EXPECT_THAT(error_of([&] { PrintedTransparency(design, printer, path, 1.0, 0); }),
                HasSubstr("encode the pattern at the printer's resolution"));
}

TEST(PrinterForPattern, ThePatternsRecordUnlessAnotherIsAskedFor) {
    const TempDir dir;
    const optics::Design design = bundled_design(2);
    const PrinterProfile inkjet = load_printer("inkjet_720");
    auto attributes = printer_attributes(inkjet);
    attributes["white"] = "0.8";
    const auto recorded = write_test_pattern(dir, design, inkjet, 0.5f, attributes);
    // Nothing asked: the recorded profile, whole.
    EXPECT_EQ(printer_toml(printer_for_pattern(design, recorded, "")), printer_toml(inkjet));
    // The same profile asked for by name: accepted.
    EXPECT_EQ(printer_for_pattern(design, recorded, "inkjet_720").name, inkjet.name);
    // Another: an error naming both and what differs.
    const std::string message =
        error_of([&] { printer_for_pattern(design, recorded, "epson_stylus_pro_4800"); });
    EXPECT_THAT(message, HasSubstr("rfd:printer: the pattern was encoded for printer 'generic 720 dpi inkjet', but "
                                   "--printer epson_stylus_pro_4800 is 'Epson Stylus Pro 4800' (dpi 720 x 720 against "
                                   "2880 x 1440, tone values, 1 sheet(s) against 2)"));
    // A pattern without a record: the Epson's tone values at the resolution the file records.
    const TempDir other;
    const auto bare = write_test_pattern(other, design, inkjet, 0.5f);
    const PrinterProfile fallback = printer_for_pattern(design, bare, "");
    EXPECT_EQ(fallback.dpi_x.value, 720);
    EXPECT_EQ(fallback.dpi_y.value, 720);
    EXPECT_EQ(fallback.gamma, load_printer("epson_stylus_pro_4800").gamma);
    EXPECT_EQ(printer_for_pattern(design, bare, "laser_1200").name, load_printer("laser_1200").name);
    // A damaged record names the file and the attribute.
    const TempDir damaged;
    const auto broken = write_test_pattern(damaged, design, inkjet, 0.5f, {{"printer_profile", "[printer]\nname = 3\n"}});
    EXPECT_THAT(error_of([&] { printer_for_pattern(design, broken, ""); }),
                HasSubstr("(rfd:printer_profile)"));
}

// ----------------------------------------------------------------------------- tone mapping

TEST(PrinterProfile, ForwardModelInvertsExactly) {
    const PrinterProfile p = parse_printer(small_printer_toml(720, 720), "test.toml");
    const double ink = std::pow(10.0, -2.0);
    EXPECT_DOUBLE_EQ(p.ink_transmittance(), ink);
    EXPECT_DOUBLE_EQ(p.transmittance(0.0), 1.0);   // bare film
    EXPECT_NEAR(p.transmittance(1.0), ink, 1e-15); // full ink: 10^-D
    for (int k = 0; k <= 100; ++k) {
        const double v = k / 100.0;
        EXPECT_NEAR(p.printer_value(p.transmittance(v)), v, 1e-9) << v;
        const double t = ink + (1.0 - ink) * k / 100.0;
        EXPECT_NEAR(p.transmittance(p.printer_value(t)), t, 1e-12) << t;
        // The model of the header, written out independently.
        EXPECT_NEAR(p.transmittance(v), ink + (1 - ink) * std::pow(1 - v, 2.2), 1e-15);
    }
    // Out of range asks for the nearest printable value.
    EXPECT_DOUBLE_EQ(p.printer_value(0.0), 1.0);
    EXPECT_DOUBLE_EQ(p.printer_value(1.5), 0.0);
}

TEST(PrinterProfile, MeasuredCurveIsReadInDensityAndInvertsExactly) {
    // max_density 2: full ink transmits 0.01, the table's last entry.
    const std::string table = "[tone]\nink = [0, 0.25, 0.5, 1]\ntransmittance = [1, 0.6, 0.2, 0.01]\n";
    const PrinterProfile p = parse_printer(small_printer_toml(720, 720) + table, "measured.toml");
    const double ink[] = {0, 0.25, 0.5, 1}, t[] = {1, 0.6, 0.2, 0.01};
    for (int k = 0; k < 4; ++k) {
        EXPECT_NEAR(p.transmittance(ink[k]), t[k], 1e-15) << k;
        EXPECT_NEAR(p.printer_value(t[k]), ink[k], 1e-12) << k;
    }
    // Between entries, straight in density: halfway from 0.5 to 1 is the geometric mean.
    EXPECT_NEAR(p.transmittance(0.75), std::sqrt(0.2 * 0.01), 1e-15);
    EXPECT_NEAR(p.transmittance(0.125), std::sqrt(1.0 * 0.6), 1e-15);
    int checked = 0;
    for (int k = 0; k <= 200; ++k) {
        const double v = k / 200.0;
        EXPECT_NEAR(p.printer_value(p.transmittance(v)), v, 1e-12) << v;
        if (k > 0) {
            EXPECT_LT(p.transmittance(v), p.transmittance((k - 1) / 200.0)) << v;
        }
        ++checked;
    }
    EXPECT_EQ(checked, 201);
    EXPECT_DOUBLE_EQ(p.printer_value(0.001), 1.0);  // darker than full ink: full ink
    // Written and read back: the same profile, the same text.
    EXPECT_EQ(printer_toml(parse_printer(printer_toml(p), "again.toml")), printer_toml(p));
    EXPECT_THAT(printer_toml(p), HasSubstr("[tone]"));
}

TEST(PrinterProfile, RefusesMeasuredCurvesItCannotInvert) {
    const auto error_for = [](const std::string& table) {
        return error_of([&] { parse_printer(small_printer_toml(720, 720) + "[tone]\n" + table, "bad.toml"); });
    };
    EXPECT_THAT(error_for("ink = [0, 0.5, 0.4, 1]\ntransmittance = [1, 0.5, 0.2, 0.01]\n"),
                AllOf(HasSubstr("tone.ink"), HasSubstr("increasing")));
    EXPECT_THAT(error_for("ink = [0, 0.5, 1]\ntransmittance = [1, 0.5, 0.6]\n"),
                AllOf(HasSubstr("tone.transmittance"), HasSubstr("fall")));
    EXPECT_THAT(error_for("ink = [0, 0.5, 1]\ntransmittance = [1, 0.01]\n"), HasSubstr("one transmittance per ink"));
    EXPECT_THAT(error_for("ink = [0.1, 0.5, 1]\ntransmittance = [1, 0.5, 0.01]\n"), HasSubstr("from 0"));
    EXPECT_THAT(error_for("ink = [0, 0.5, 1]\ntransmittance = [0.9, 0.5, 0.01]\n"), HasSubstr("1 (bare film)"));
    EXPECT_THAT(error_for("ink = [0, 0.5, 1]\ntransmittance = [1, 0.5, 0.05]\n"), HasSubstr("max_density"));
    EXPECT_THAT(error_for("ink = [0, 0.5, 1]\ntransmittance = [1, \"a\", 0.01]\n"), HasSubstr("numbers"));
}

TEST(ToneMap, TwoSheetsMultiplyToTheBlackCorrectedTarget) {
    const PrinterProfile p = parse_printer(small_printer_toml(720, 720), "test.toml");
    const double b = 0.012;
    for (const int sheets : {1, 2}) {
        ToneMap tone{p, 1.5, 0.8, sheets};
        for (int k = 0; k <= 40; ++k) {
            const double value = k / 40.0;
            const double target = std::min(1.0, 1.5 * value / 0.8);
            const double black = std::pow(b, sheets);
            const double stack = black + (1 - black) * target;
            // What the printed sheets transmit, through the forward model, stacked.
            const double one_sheet = p.transmittance(tone.printer_value(value));
            EXPECT_NEAR(std::pow(one_sheet, sheets), stack, 1e-12) << sheets << " " << value;
            EXPECT_NEAR(tone.stack_transmittance(value), stack, 1e-15);
        }
        // Black prints the black level per sheet; anything at or above white prints no ink.
        EXPECT_NEAR(p.transmittance(tone.printer_value(0.0)), b, 1e-12);
        EXPECT_DOUBLE_EQ(tone.printer_value(1.01 * 0.8 / 1.5), 0.0);
        EXPECT_DOUBLE_EQ(tone.printer_value(7.0), 0.0);
    }
}

// ----------------------------------------------------------------------------- profiles

TEST(PrinterProfile, BundledProfilesLoad) {
    const PrinterProfile epson = load_printer("epson_stylus_pro_4800");
    EXPECT_EQ(epson.dpi_x.value, 2880);
    EXPECT_EQ(epson.dpi_y.value, 1440);
    EXPECT_EQ(epson.sheets, 2);
    EXPECT_EQ(epson.paper.width, 210);
    EXPECT_EQ(epson.paper.height, 297);
    EXPECT_EQ(load_printer("laser_1200").dpi_y.value, 1200);
    EXPECT_EQ(load_printer("inkjet_720").dpi_x.value, 720);
    EXPECT_THAT(error_of([] { load_printer("no_such_printer"); }),
                HasSubstr("no such file or bundled profile (bundled: "));
}

TEST(PrinterProfile, TomlReadsBackToTheSameProfile) {
    for (const auto& entry : std::filesystem::directory_iterator(bundled_printer_folder())) {
        const PrinterProfile bundled = load_printer(entry.path().string());
        const PrinterProfile read = parse_printer(printer_toml(bundled), "round_trip.toml");
        EXPECT_EQ(read.name, bundled.name);
        EXPECT_EQ(read.dpi_x.value, bundled.dpi_x.value);
        EXPECT_EQ(read.dpi_y.value, bundled.dpi_y.value);
        EXPECT_EQ(read.gamma, bundled.gamma);
        EXPECT_EQ(read.max_density, bundled.max_density);
        EXPECT_EQ(read.black_level, bundled.black_level);
        EXPECT_EQ(read.sheets, bundled.sheets);
        EXPECT_EQ(read.film, bundled.film);
        EXPECT_EQ(read.paper.name, bundled.paper.name);
        EXPECT_EQ(read.paper.width, bundled.paper.width);
        EXPECT_EQ(read.paper.height, bundled.paper.height);
        EXPECT_EQ(read.paper.margin, bundled.paper.margin);
        EXPECT_EQ(printer_toml(read), printer_toml(bundled)) << entry.path();
    }
    // Values that need every digit, and a name that needs escaping.
    PrinterProfile odd = parse_printer(small_printer_toml(720, 360), "odd.toml");
    odd.name = "say \"hi\"\\ \u00e9";
    odd.gamma = 1.0 / 3.0;
    odd.black_level = 0.1 + 0.2;
    const PrinterProfile read = parse_printer(printer_toml(odd), "odd.toml");
    EXPECT_EQ(read.name, odd.name);
    EXPECT_EQ(read.gamma, odd.gamma);
    EXPECT_EQ(read.black_level, odd.black_level);
}

TEST(PrinterProfile, BadKeysNameFileLineAndKey) {
    std::string text = small_printer_toml(720, 720);
    text.replace(text.find("gamma"), 5, "gama");
    EXPECT_THAT(error_of([&] { parse_printer(text, "typo.toml"); }),
                MatchesRegex("typo\\.toml:5:[0-9]+: printer\\.gama: unknown key \\(did you mean 'gamma'\\?\\)"));
    std::string unknown = small_printer_toml(720, 720) + "colour = 3\n";
    EXPECT_THAT(error_of([&] { parse_printer(unknown, "unknown.toml"); }),
                MatchesRegex("unknown\\.toml:14:.*paper\\.colour: unknown key.*"));
    std::string too_black = small_printer_toml(720, 720);
    too_black.replace(too_black.find("black_level = 0.012"), 19, "black_level = 0.001");
    EXPECT_THAT(error_of([&] { parse_printer(too_black, "black.toml"); }),
                MatchesRegex("black\\.toml:7:.*black_level: black level 0\\.001.* darker than full ink.*"));
    std::string no_room = small_printer_toml(720, 720, 50, 60);
    no_room.replace(no_room.find("margin_mm = 1"), 13, "margin_mm = 30");
    EXPECT_THAT(error_of([&] { parse_printer(no_room, "margin.toml"); }), HasSubstr("no printable area"));
}

// ----------------------------------------------------------------------------- TIFF sheets

TEST(SheetTiff, ResolutionTagsAndMarkersWhereTheDesignPutsTheCornerLenslets) {
    TempDir dir;
    const optics::Design design = bundled_design(2);
    const PrinterProfile printer = parse_printer(small_printer_toml(1200, 600), "test.toml");
    const auto pattern = write_test_pattern(dir, design, printer, 0.4f);
    SheetOptions options;
    options.rows_per_strip = 37;  // strips that do not divide the page
    const SheetReport report = write_sheet(dir / "sheet.tif", design, printer, pattern, options);
    const Page page = read_page(dir / "sheet.tif");

    EXPECT_EQ(page.spec.dpi_x, 1200.0);
    EXPECT_EQ(page.spec.dpi_y, 600.0);
    EXPECT_EQ(page.spec.channels, 3);
    EXPECT_EQ(page.spec.type, SampleType::UInt8);
    // The page: whole dots inside 50 x 60 mm.
    const int page_w = static_cast<int>(std::floor(50.0 * 1200 / 25.4)), page_h = static_cast<int>(std::floor(60.0 * 600 / 25.4));
    ASSERT_EQ(page.width, page_w);
    ASSERT_EQ(page.height, page_h);

    // Where the design puts the corner lenslets: lattice centres through the raster's
    // geometry, plus the centring offset.
    const auto g = patterns::pattern_geometry(design, Dpi{1200}, Dpi{600});
    const int offset_x = (page_w - g.width) / 2, offset_y = (page_h - g.height) / 2;
    const optics::DesignOptics optics(design);
    const optics::Lattice& lattice = optics.lattice();
    const double inradius = 0.5 * std::min(lattice.pitch_x(), lattice.pitch_y());
    int found = 0;
    double worst = 0.0;
    for (const optics::CellIndex cell : {optics::CellIndex{0, 0}, {lattice.count_x() - 1, 0}, {0, lattice.count_y() - 1},
                                         {lattice.count_x() - 1, lattice.count_y() - 1}}) {
        const Eigen::Vector2d centre = lattice.center(cell);
        const Eigen::Vector2d expected = g.raster_position(centre) + Eigen::Vector2d(offset_x, offset_y);
        // Centroid of the ink inside the cell's inscribed circle (all of it clear but the marker).
        double sum = 0, sx = 0, sy = 0;
        int clear = 0, dots = 0;
        for (int y = 0; y < page.height; ++y)
            for (int x = 0; x < page.width; ++x) {
                const Eigen::Vector2d mm = g.dot_centre(x - offset_x, y - offset_y);
                if ((mm - centre).norm() > 0.95 * inradius) continue;
                const double ink = 1.0 - page.code(x, y) / 255.0;
                sum += ink;
                sx += ink * x;
                sy += ink * y;
                ++dots;
                clear += page.code(x, y) == 255;
            }
        ASSERT_GT(sum, 10.0);
        EXPECT_NEAR(sx / sum, expected.x(), 0.5) << cell.i << "," << cell.j;
        EXPECT_NEAR(sy / sum, expected.y(), 0.5) << cell.i << "," << cell.j;
        worst = std::max({worst, std::abs(sx / sum - expected.x()), std::abs(sy / sum - expected.y())});
        // The cell is printed clear around the marker's lines: the pattern is replaced.
        EXPECT_GT(clear, dots / 2);
        ++found;
    }
    EXPECT_EQ(found, 4);
    RecordProperty("worst_marker_offset_dots", std::to_string(worst));
    ASSERT_EQ(report.layout.markers.size(), 4u);

    // A pattern dot away from the marks carries the tone-mapped value, computed here from
    // the model of printer.hpp: t = 0.4 / 0.8 stacked on two sheets.
    const double b2 = 0.012 * 0.012, ink = 0.01;
    const double sheet = std::sqrt(b2 + (1 - b2) * 0.5);
    const double code = std::pow((sheet - ink) / (1 - ink), 1 / 2.2);
    const Eigen::Vector2d middle = g.raster_position(lattice.center({2, 2}) + Eigen::Vector2d(0.5, 0.3));
    EXPECT_NEAR(page.code(static_cast<int>(middle.x()) + offset_x, static_cast<int>(middle.y()) + offset_y), 255 * code,
                0.51);
    // Bare paper outside the pattern and its marks.
    EXPECT_EQ(page.code(2, page.height / 2), 255);
}

TEST(SheetTiff, MirrorIsTheExactLeftRightMirrorAndRerunsAreIdentical) {
    TempDir dir;
    const optics::Design design = bundled_design(2);
    const PrinterProfile printer = parse_printer(small_printer_toml(600, 300), "test.toml");
    const auto pattern = write_test_pattern(dir, design, printer, 0.3f);
    write_sheet(dir / "front.tif", design, printer, pattern, {});
    write_sheet(dir / "front_again.tif", design, printer, pattern, {});
    SheetOptions mirrored;
    mirrored.mirror = true;
    write_sheet(dir / "back.tif", design, printer, pattern, mirrored);
    EXPECT_EQ(read_bytes(dir / "front.tif"), read_bytes(dir / "front_again.tif"));

    const Page front = read_page(dir / "front.tif"), back = read_page(dir / "back.tif");
    ASSERT_EQ(front.width, back.width);
    ASSERT_EQ(front.height, back.height);
    // The label differs (front / back), so compare everything from the pattern's top row
    // down: the pattern, markers, crop marks and ruler.
    const auto g = patterns::pattern_geometry(design, Dpi{600}, Dpi{300});
    const int label_bottom = (front.height - g.height) / 2;
    long long differing = 0, inked = 0;
    for (int y = label_bottom; y < front.height; ++y)
        for (int x = 0; x < front.width; ++x) {
            differing += front.code(x, y) != back.code(front.width - 1 - x, y);
            inked += front.code(x, y) < 128;
        }
    EXPECT_EQ(differing, 0);
    EXPECT_GT(inked, 1000);  // the comparison saw the marks and the pattern
}

// The page preview: the paper's shape at 800 pixels along its longer side, the pattern's dots
// printed with the sheet's tone (at 300 dpi a dot is taller than a preview pixel: none may
// be left without a dot), and over the pattern's rectangle as poppler draws the PDF of
// the same sheet at that scale (mean code within 2 of 255; the label's text is hinted
// differently, so the page as a whole differs by more).
TEST(SheetPreview, ThePageAsPrintedAtScreenSize) {
    TempDir dir;
    const optics::Design design = bundled_design(2);
    const PrinterProfile printer = parse_printer(small_printer_toml(600, 300), "test.toml");
    const auto pattern = write_test_pattern(dir, design, printer, 0.3f);
    SheetOptions options;
    options.preview = dir / "front.png";
    const SheetReport report = write_sheet(dir / "front.pdf", design, printer, pattern, options);
    const Page preview = read_page(dir / "front.png");
    EXPECT_EQ(preview.height, kPagePreviewPixels);  // 60 mm paper, the longer side
    EXPECT_EQ(preview.width, 667);                   // 50 mm: 800 * 50 / 60
    const double px_per_mm = kPagePreviewPixels / 60.0;
    const Eigen::Vector2d centre = 0.5 * (report.layout.pattern_min() + report.layout.pattern_max()) * px_per_mm;
    const int expected = static_cast<int>(std::lround(255.0 * (1.0 - report.tone.printer_value(0.3))));
    EXPECT_NEAR(preview.code(static_cast<int>(centre.x()), static_cast<int>(centre.y())), expected, 1);

    options.preview = dir / "wrong.jpg";
    EXPECT_THAT(error_of([&] { write_sheet(dir / "x.pdf", design, printer, pattern, options); }),
                HasSubstr("--preview: expected a .png file"));

    const std::string pdftoppm = RFD_PDFTOPPM;
    if (pdftoppm.empty()) GTEST_SKIP() << "poppler-utils (pdftoppm) not installed";
    const std::string command = pdftoppm + " -scale-to 800 -png -singlefile " + (dir / "front.pdf").string() + " " +
                                (dir / "poppler").string();
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    const Page poppler = read_page(dir / "poppler.png");
    ASSERT_EQ(poppler.width, preview.width);
    ASSERT_EQ(poppler.height, preview.height);
    const Eigen::Vector2d lo = report.layout.pattern_min() * px_per_mm, hi = report.layout.pattern_max() * px_per_mm;
    double ours = 0.0, theirs = 0.0, pixels = 0.0;
    for (int y = static_cast<int>(lo.y()) + 2; y < static_cast<int>(hi.y()) - 2; ++y)
        for (int x = static_cast<int>(lo.x()) + 2; x < static_cast<int>(hi.x()) - 2; ++x) {
            ours += preview.code(x, y);
            theirs += poppler.code(x, y);
            pixels += 1.0;
        }
    ASSERT_GT(pixels, 1000.0);
    EXPECT_NEAR(ours / pixels, theirs / pixels, 2.0);
}

// Copies: as many as fit, each block (pattern and its room for marks) inside the printable
// area, none overlapping another, one more column or row would not fit; in the TIFF every
// copy's dots are the first copy's, dot for dot; too many asked for says how many fit.
TEST(SheetCopies, AsManyAsFitEachTheSamePrint) {
    TempDir dir;
    const optics::Design design = bundled_design(2);
    const PrinterProfile printer = parse_printer(small_printer_toml(300, 150, 120, 150), "test.toml");
    const auto g = patterns::pattern_geometry(design, printer.dpi_x, printer.dpi_y);
    patterns::write_pattern(dir / "steps.exr", Steps(g), {{"white", "0.8"}});
    SheetOptions options;
    options.copies = 0;
    const SheetLayout l = write_sheet(dir / "copies.tif", design, printer, dir / "steps.exr", options).layout;
    ASSERT_GT(l.copies.size(), 1u);
    const Eigen::Vector2d size = g.size_mm();
    const double margin = printer.paper.margin;
    std::set<int> columns, rows;
    for (std::size_t k = 0; k < l.copies.size(); ++k) {
        const Eigen::Vector2d lo = l.pattern_min() + l.copy_mm(k), hi = l.pattern_max() + l.copy_mm(k);
        EXPECT_GE(lo.x() - kSideRoom, margin - 1e-9) << k;
        EXPECT_LE(hi.x() + kSideRoom, printer.paper.width - margin + 1e-9) << k;
        EXPECT_GE(lo.y() - kTopRoom, margin - 1e-9) << k;
        EXPECT_LE(hi.y() + kBottomRoom, printer.paper.height - margin + 1e-9) << k;
        for (std::size_t j = 0; j < k; ++j) {
            const Eigen::Vector2d d = (l.copy_mm(k) - l.copy_mm(j)).cwiseAbs();
            EXPECT_TRUE(d.x() >= size.x() + 2 * kSideRoom - 1e-9 || d.y() >= size.y() + kTopRoom + kBottomRoom - 1e-9)
                << k << " overlaps " << j;
        }
        columns.insert(l.copies[k].x());
        rows.insert(l.copies[k].y());
    }
    EXPECT_EQ(l.copies.size(), columns.size() * rows.size());
    EXPECT_GT(static_cast<double>(columns.size() + 1) * (size.x() + 2 * kSideRoom), printer.paper.width - 2 * margin);
    EXPECT_GT(static_cast<double>(rows.size() + 1) * (size.y() + kTopRoom + kBottomRoom), printer.paper.height - 2 * margin);

    const Page page = read_page(dir / "copies.tif");
    long long differing = 0;
    for (std::size_t k = 1; k < l.copies.size(); ++k)
        for (int y = 0; y < g.height; ++y)
            for (int x = 0; x < g.width; ++x)
                for (int c = 0; c < 3; ++c)
                    differing += page.code(l.offset_x + x, l.offset_y + y, c) !=
                                 page.code(l.offset_x + l.copies[k].x() + x, l.offset_y + l.copies[k].y() + y, c);
    EXPECT_EQ(differing, 0);

    options.copies = static_cast<int>(l.copies.size()) + 1;
    EXPECT_THAT(error_of([&] { write_sheet(dir / "more.pdf", design, printer, dir / "steps.exr", options); }),
                HasSubstr("copies of the pattern do not fit on test paper: at most " + std::to_string(l.copies.size())));
}

TEST(SheetTiff, SixteenBitsKeepTheResolution) {
    TempDir dir;
    const optics::Design design = bundled_design(2);
    const PrinterProfile printer = parse_printer(small_printer_toml(300, 150), "test.toml");
    const auto pattern = write_test_pattern(dir, design, printer, 0.5f);
    SheetOptions options;
    options.bits = 16;
    write_sheet(dir / "sheet16.tif", design, printer, pattern, options);
    const ImageFileReader in(dir / "sheet16.tif");
    EXPECT_EQ(in.spec().type, SampleType::UInt16);
    EXPECT_EQ(in.spec().dpi_x, 300.0);
    EXPECT_EQ(in.spec().dpi_y, 150.0);
}

// ----------------------------------------------------------------------------- PDF sheets

// The four numbers of the PDF's first /MediaBox [x0 y0 x1 y1]. (No std::regex: GCC 12's
// <regex> trips -Wmaybe-uninitialized under the sanitizer build.)
double media_box_value(const std::string& pdf, int index) {
    const std::size_t at = pdf.find("/MediaBox [");
    EXPECT_NE(at, std::string::npos);
    if (at == std::string::npos) return -1.0;
    std::istringstream in(pdf.substr(at + 11, 100));
    double values[4] = {-1, -1, -1, -1};
    in >> values[0] >> values[1] >> values[2] >> values[3];
    return values[index];
}

// The number after `key` at or after `from`.
long long number_after(const std::string& pdf, const std::string& key, std::size_t from) {
    const std::size_t at = pdf.find(key, from);
    if (at == std::string::npos) return -1;
    return std::stoll(pdf.substr(at + key.size(), 20));
}

TEST(SheetPdf, PageIsThePaperSizeAndReRunsAreIdentical) {
    TempDir dir;
    const optics::Design design = bundled_design(2);
    const PrinterProfile printer = parse_printer(small_printer_toml(720, 360), "test.toml");
    const auto pattern = write_test_pattern(dir, design, printer, 0.5f);
    write_sheet(dir / "sheet.pdf", design, printer, pattern, {});
    write_sheet(dir / "again.pdf", design, printer, pattern, {});
    const std::string pdf = read_bytes(dir / "sheet.pdf");
    EXPECT_EQ(pdf, read_bytes(dir / "again.pdf"));
    EXPECT_NEAR(media_box_value(pdf, 2), 50.0 / 25.4 * 72.0, 1e-3);
    EXPECT_NEAR(media_box_value(pdf, 3), 60.0 / 25.4 * 72.0, 1e-3);
}

TEST(SheetPdf, RasterWiderThanCairosLimitIsTiled) {
    TempDir dir;
    const optics::Design design = bundled_design(2);
    // 40000 dpi across: Design II's 24 mm are 37796 dots, beyond Cairo's 32767.
    const PrinterProfile printer = parse_printer(small_printer_toml(40000, 60), "test.toml");
    const auto pattern = write_test_pattern(dir, design, printer, 0.5f);
    const auto g = patterns::pattern_geometry(design, Dpi{40000}, Dpi{60});
    ASSERT_GT(g.width, 32767);
    write_sheet(dir / "wide.pdf", design, printer, pattern, {});
    const std::string pdf = read_bytes(dir / "wide.pdf");
    // Every image tile, kPdfTile dots apart, each reaching under the next by the overlap
    // (the last to the raster's edge); one band of rows.
    const int overlap = pdf_tile_overlap(40000);
    EXPECT_EQ(overlap, kPdfTile / 8);
    int tiles = 0;
    for (std::size_t at = pdf.find("/Subtype /Image"); at != std::string::npos; at = pdf.find("/Subtype /Image", at + 1)) {
        EXPECT_EQ(number_after(pdf, "/Width ", at), std::min(kPdfTile + overlap, g.width - tiles * kPdfTile)) << tiles;
        EXPECT_EQ(number_after(pdf, "/Height ", at), g.height);
        ++tiles;
    }
    EXPECT_EQ(tiles, (g.width + kPdfTile - 1) / kPdfTile);
}

// Anti-aliased viewers must not show the tile joins: a uniform pattern's sheet rendered at
// 150 dpi by poppler, through both of its renderers (Splash: pdftoppm; Cairo: pdftocairo, as
// evince draws), has no column or row at a join that differs from the pattern a few pixels
// away. Each join of Design II at 2880 dpi falls inside a 150 dpi pixel (2048 dots = 106.7
// px). Skipped only when poppler-utils is missing (scripts/install-deps.sh installs it).
TEST(SheetPdf, TileJoinsDoNotShowInAntiAliasedViewers) {
    const std::string pdftoppm = RFD_PDFTOPPM, pdftocairo = RFD_PDFTOCAIRO;
    if (pdftoppm.empty() || pdftocairo.empty()) GTEST_SKIP() << "poppler-utils (pdftoppm, pdftocairo) not installed";
    TempDir dir;
    const optics::Design design = bundled_design(2);
    const PrinterProfile printer = parse_printer(small_printer_toml(2880, 2880), "test.toml");
    const auto pattern = write_test_pattern(dir, design, printer, 0.5f);
    const SheetLayout layout = write_sheet(dir / "sheet.pdf", design, printer, pattern, {}).layout;
    ASSERT_GT(layout.pattern.width, kPdfTile);
    ASSERT_GT(layout.pattern.height, kPdfTile);
    constexpr double kViewerDpi = 150.0;
    const double px_per_mm = kViewerDpi / 25.4;
    for (const std::string& renderer : {pdftoppm, pdftocairo}) {
        SCOPED_TRACE(renderer);
        const std::string command = renderer + " -r 150 -png -singlefile " + (dir / "sheet.pdf").string() + " " +
                                    (dir / "view").string();
        ASSERT_EQ(std::system(command.c_str()), 0) << command;
        const Page view = read_page(dir / "view.png");
        // The pattern's extent in viewer pixels, and a band across its middle, clear of the
        // markers at its corner lenslets and of the joins the other way.
        const Eigen::Vector2d lo = layout.pattern_min() * px_per_mm, hi = layout.pattern_max() * px_per_mm;
        const auto band = [](double a, double b) { return std::pair<int, int>(static_cast<int>(a + 0.3 * (b - a)), static_cast<int>(a + 0.6 * (b - a))); };
        // Named copies, not structured bindings: lambdas capture those only from clang 16.
        const std::pair<int, int> rows = band(lo.y(), hi.y()), cols = band(lo.x(), hi.x());
        const int row0 = rows.first, row1 = rows.second, col0 = cols.first, col1 = cols.second;
        auto column = [&](int x) {
            double sum = 0.0;
            for (int y = row0; y < row1; ++y) sum += view.code(x, y);
            return sum / (row1 - row0);
        };
        auto row = [&](int y) {
            double sum = 0.0;
            for (int x = col0; x < col1; ++x) sum += view.code(x, y);
            return sum / (col1 - col0);
        };
        const double gray = column(col0);
        EXPECT_GT(gray, 20.0);  // a gray, not the white paper
        EXPECT_LT(gray, 235.0);
        for (int tx = kPdfTile; tx < layout.pattern.width; tx += kPdfTile) {
            const int at = static_cast<int>((layout.offset_x + tx) * layout.dot_x * px_per_mm);
            for (int x = at - 1; x <= at + 1; ++x)
                EXPECT_NEAR(column(x), 0.5 * (column(at - 5) + column(at + 5)), 1.0) << "column " << x << ", join at dot " << tx;
        }
        for (int ty = kPdfTile; ty < layout.pattern.height; ty += kPdfTile) {
            const int at = static_cast<int>((layout.offset_y + ty) * layout.dot_y * px_per_mm);
            for (int y = at - 1; y <= at + 1; ++y)
                EXPECT_NEAR(row(y), 0.5 * (row(at - 5) + row(at + 5)), 1.0) << "row " << y << ", join at dot " << ty;
        }
    }
}

// The overlap must not move a dot: rendered at the printer's own resolution around the
// corner where four tiles meet, every pixel is its pattern dot's printer code (a pattern
// whose every dot differs from its neighbours). Rendered by poppler's Cairo renderer, which
// maps an image whose edges lie on pixels one dot to one pixel (its Splash renderer,
// pdftoppm, draws such an image a pixel wider, stretched: a repeated column).
TEST(SheetPdf, EveryDotAtATileJoinIsThePatternsAtThePrintersResolution) {
    const std::string pdftocairo = RFD_PDFTOCAIRO;
    if (pdftocairo.empty()) GTEST_SKIP() << "poppler-utils (pdftocairo) not installed";
    TempDir dir;
    const optics::Design design = bundled_design(2);
    // A paper of whole dots (2 x 2.5 inches): PDF puts the origin at the page's foot, and a
    // fractional page height would shift a renderer that does not snap images to pixels.
    const PrinterProfile printer = parse_printer(small_printer_toml(2880, 2880, 50.8, 63.5), "test.toml");
    const auto g = patterns::pattern_geometry(design, printer.dpi_x, printer.dpi_y);
    patterns::write_pattern(dir / "steps.exr", Steps(g), {{"white", "0.8"}});
    const SheetReport report = write_sheet(dir / "sheet.pdf", design, printer, dir / "steps.exr", {});
    const SheetLayout& layout = report.layout;
    ASSERT_GT(g.width, kPdfTile + 32);
    ASSERT_GT(g.height, kPdfTile + 32);
    constexpr int kHalf = 24;  // pixels either side of the joins
    const int x0 = layout.offset_x + kPdfTile - kHalf, y0 = layout.offset_y + kPdfTile - kHalf;
    const std::string command = pdftocairo + " -r 2880 -x " + std::to_string(x0) + " -y " + std::to_string(y0) +
                                " -W " + std::to_string(2 * kHalf) + " -H " + std::to_string(2 * kHalf) +
                                " -png -singlefile " + (dir / "sheet.pdf").string() + " " + (dir / "dots").string();
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    const Page view = read_page(dir / "dots.png");
    ASSERT_EQ(view.width, 2 * kHalf);
    ASSERT_EQ(view.height, 2 * kHalf);
    int wrong = 0;
    for (int y = 0; y < view.height; ++y)
        for (int x = 0; x < view.width; ++x)
            for (int c = 0; c < 3; ++c) {
                const int px = x0 + x - layout.offset_x, py = y0 + y - layout.offset_y;
                const int expected = static_cast<int>(std::lround(
                    255.0f * static_cast<float>(1.0 - report.tone.printer_value(Steps::value(px, py, c)))));
                if (view.code(x, y, c) != expected && ++wrong <= 5)
                    ADD_FAILURE() << "dot (" << px << ", " << py << ") channel " << c << ": " << view.code(x, y, c)
                                  << ", expected " << expected;
            }
    EXPECT_EQ(wrong, 0);
}

// ----------------------------------------------------------------------------- bad input

TEST(Sheet, PatternOfTheWrongSizeSaysBothSizes) {
    TempDir dir;
    const optics::Design design = bundled_design(2);
    const PrinterProfile at_720 = parse_printer(small_printer_toml(720, 720), "a.toml");
    const PrinterProfile at_600 = parse_printer(small_printer_toml(600, 300), "b.toml");
    const auto pattern = write_test_pattern(dir, design, at_720, 0.5f);
    const auto g = patterns::pattern_geometry(design, Dpi{600}, Dpi{300});
    const std::string message = error_of([&] { write_sheet(dir / "sheet.tif", design, at_600, pattern, {}); });
    EXPECT_THAT(message, HasSubstr("the pattern is 681 x 681 dots at 720 x 720 dpi"));
    EXPECT_THAT(message, HasSubstr("needs " + std::to_string(g.width) + " x " + std::to_string(g.height) + " dots"));
    EXPECT_FALSE(std::filesystem::exists(dir / "sheet.tif"));
}

TEST(Sheet, UnwritableOutputLeavesNothingBehind) {
    TempDir dir;
    const optics::Design design = bundled_design(2);
    const PrinterProfile printer = parse_printer(small_printer_toml(300, 150), "test.toml");
    const auto pattern = write_test_pattern(dir, design, printer, 0.5f);
    // A directory where the file should go: the rename fails after the whole sheet is written.
    std::filesystem::create_directory(dir / "taken.tif");
    std::filesystem::create_directory(dir / "taken.pdf");
    for (const char* name : {"taken.tif", "taken.pdf"}) {
        try {
            write_sheet(dir / name, design, printer, pattern, {});
            ADD_FAILURE() << "no error for " << name;
        } catch (const IoError& error) {
            EXPECT_EQ(error.exit_code(), 3);
        }
    }
    EXPECT_THAT(error_of([&] { write_sheet(dir / "missing" / "sheet.tif", design, printer, pattern, {}); }),
                HasSubstr("missing"));
    std::vector<std::string> left;
    for (const auto& entry : std::filesystem::directory_iterator(dir.path())) left.push_back(entry.path().filename());
    std::sort(left.begin(), left.end());
    EXPECT_EQ(left, (std::vector<std::string>{"pattern.exr", "taken.pdf", "taken.tif"}));
    EXPECT_TRUE(std::filesystem::is_empty(dir / "taken.tif"));
}

TEST(Sheet, BadOptionsAndAttributes) {
    TempDir dir;
    const optics::Design design = bundled_design(2);
    const PrinterProfile printer = parse_printer(small_printer_toml(300, 150), "test.toml");
    const auto pattern = write_test_pattern(dir, design, printer, 0.5f, {{"white", "bright"}});
    EXPECT_THAT(error_of([&] { write_sheet(dir / "s.tif", design, printer, pattern, {}); }),
                HasSubstr("rfd:white: expected a positive number, got 'bright'"));
    SheetOptions options;
    options.sheets = 3;
    EXPECT_THAT(error_of([&] { write_sheet(dir / "s.tif", design, printer, pattern, options); }),
                HasSubstr("--sheets: expected 1 or 2, got 3"));
    EXPECT_THAT(error_of([&] { write_sheet(dir / "s.png", design, printer, pattern, {}); }),
                HasSubstr("expected .tif, .tiff or .pdf"));
    // A mirrored page alone would show the pattern flipped: it is the back of two sheets.
    SheetOptions mirrored_alone;
    mirrored_alone.mirror = true;
    mirrored_alone.sheets = 1;
    EXPECT_THAT(error_of([&] { write_sheet(dir / "s.tif", design, printer, pattern, mirrored_alone); }),
                HasSubstr("--mirror: a mirrored page is the back sheet of two, but this print has one sheet (--sheets 1)"));
    EXPECT_FALSE(std::filesystem::exists(dir / "s.tif"));
    // Design I does not fit the test printer's small paper.
    const optics::Design big = bundled_design(1);
    const PrinterProfile coarse = parse_printer(small_printer_toml(100, 100), "coarse.toml");
    const auto big_pattern = dir / "big.exr";
    patterns::write_pattern(big_pattern, Uniform(patterns::pattern_geometry(big, Dpi{100}, Dpi{100}), 0.5f), {});
    EXPECT_THAT(error_of([&] { write_sheet(dir / "s.tif", big, coarse, big_pattern, {}); }),
                MatchesRegex(".*coarse\\.toml.*the pattern \\(1[45][0-9]\\.[0-9] x 1[45][0-9]\\.[0-9] mm\\).*do not fit "
                             "the printable area of test paper \\(48\\.0 x 58\\.0 mm\\).*"));
}

// ----------------------------------------------------------------------------- wedge

// The wedge's codes run from bare film to full ink, and the profile's prediction under each
// is T(v) from the header's formula; rendered by poppler, every patch's centre holds its code
// (the patch is an image, printed as patterns are, so no colour conversion changed it).
TEST(Wedge, PatchesCarryTheirCodesAndTheProfilesPrediction) {
    const PrinterProfile printer = load_printer("inkjet_720");
    const auto patches = wedge_patches(printer, 6);
    ASSERT_EQ(patches.size(), 6u);
    EXPECT_EQ(patches.front().code, 255);
    EXPECT_EQ(patches[1].code, 204);
    EXPECT_EQ(patches.back().code, 0);
    EXPECT_DOUBLE_EQ(patches.front().transmittance, 1.0);
    EXPECT_NEAR(patches.back().transmittance, std::pow(10.0, -printer.max_density), 1e-15);
    const double t_ink = std::pow(10.0, -printer.max_density);
    EXPECT_NEAR(patches[2].transmittance, t_ink + (1 - t_ink) * std::pow(153.0 / 255.0, printer.gamma), 1e-15);
    EXPECT_THAT(error_of([&] { wedge_patches(printer, 1); }), HasSubstr("expected 2 to 256"));

    TempDir dir;
    const auto placed = write_wedge_pdf(dir / "wedge.pdf", printer, 21, dir / "wedge.png");
    // The page's picture: every patch's centre holds its code there too.
    const Page picture = read_page(dir / "wedge.png");
    ASSERT_EQ(picture.height, kPagePreviewPixels);  // A4: 297 mm the longer side
    const double px_per_mm = kPagePreviewPixels / 297.0;
    for (const WedgePatch& patch : placed)
        EXPECT_NEAR(picture.code(static_cast<int>((patch.left + 8.0) * px_per_mm), static_cast<int>((patch.top + 8.0) * px_per_mm)),
                    patch.code, 1.0)
            << "picture, patch of code " << patch.code;
    EXPECT_THAT(error_of([&] { write_wedge_pdf(dir / "w.pdf", parse_printer(small_printer_toml(720, 720, 10, 10), "tiny.toml"), 5); }),
                HasSubstr("does not fit"));

    const std::string pdftoppm = RFD_PDFTOPPM;
    if (pdftoppm.empty()) GTEST_SKIP() << "poppler-utils (pdftoppm) not installed";
    const std::string command = pdftoppm + " -r 50 -png -singlefile " + (dir / "wedge.pdf").string() + " " +
                                (dir / "view").string();
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    const Page view = read_page(dir / "view.png");
    for (const WedgePatch& patch : placed) {
        const int x = static_cast<int>((patch.left + 8.0) * 50 / 25.4), y = static_cast<int>((patch.top + 8.0) * 50 / 25.4);
        EXPECT_NEAR(view.code(x, y), patch.code, 1.0) << "patch of code " << patch.code;
    }
}

// ----------------------------------------------------------------------------- moire

TEST(Moire, PitchRangeParsing) {
    const PitchRange r = parse_pitch_range("2.30:2.40:11", "--pitch");
    ASSERT_EQ(r.values().size(), 11u);
    EXPECT_DOUBLE_EQ(r.values().front(), 2.30);
    EXPECT_DOUBLE_EQ(r.values().back(), 2.40);
    EXPECT_NEAR(r.values()[5], 2.35, 1e-15);
    for (const char* bad : {"2.4:2.3:5", "2.3:2.4:1", "0:1:5", "-1:1:5", "2.3:2.4", "2.3:2.4:5:6", "a:2.4:5",
                            "2.3:2.4:5x", "2.3:2.3:5", "2.3:2.4:1000"})
        EXPECT_THAT(error_of([&] { parse_pitch_range(bad, "--pitch"); }),
                    HasSubstr("--pitch: expected FROM:TO:STEPS in mm with 0 < FROM < TO and 2 <= STEPS <= 200, got '" +
                              std::string(bad) + "'"))
            << bad;
}

// Design I's lenslets: 20.77 per cm^2 on a hexagonal lattice, pitch sqrt(200 / (sqrt(3) 20.77)).
TEST(Moire, DefaultHypothesesAreCentredOnTheDesignsPitch) {
    const PitchRange r = default_pitch_range(bundled_design(1));
    const double pitch = std::sqrt(200.0 / (std::sqrt(3.0) * 20.77));
    ASSERT_EQ(r.steps, 9);
    EXPECT_NEAR(r.values()[4], pitch, 1e-9);
    EXPECT_NEAR(r.to / r.from, 1.004 / 0.996, 1e-12);
}

// The lines a calibration reads from a photograph are the lines drawn: one centred in each
// band across its lines, a quarter period wide, none outside the band.
TEST(Moire, InkedIsWhereTheLinesAre) {
    const optics::Design design = bundled_design(1);
    MoireOptions options;
    options.x = parse_pitch_range("2.33:2.39:3", "--pitch");
    const MoireSheet sheet = moire_sheet(design, load_printer("epson_stylus_pro_4800"), options);
    ASSERT_EQ(sheet.bands.size(), 6u);
    int checked = 0;
    for (const MoireBand& band : sheet.bands) {
        const double cx = band.left + 0.5 * band.width, cy = band.top + 0.5 * band.height;
        // Across the lines: k periods from the centre line, plus an offset in periods.
        const auto at = [&](double periods) {
            return band.along_x ? band.inked(cx + periods * band.period, cy) : band.inked(cx, cy + periods * band.period);
        };
        for (const int k : {-1, 0, 1}) {
            EXPECT_TRUE(at(k)) << k;
            EXPECT_TRUE(at(k + 0.12)) << k;
            EXPECT_FALSE(at(k + 0.13)) << k;
            EXPECT_FALSE(at(k + 0.5)) << k;
            ++checked;
        }
        EXPECT_FALSE(band.inked(band.left - 0.01, cy));
        EXPECT_FALSE(band.inked(cx, band.top + band.height + 0.01));
        EXPECT_GE(band.left, 3.0);
        EXPECT_LE(band.left + band.width, 210.0 - 3.0);
    }
    EXPECT_EQ(checked, 18);
}

// Cairo resolves a font face once per process, with the font options of the first surface
// that draws it (a PDF's: no hinting), and keeps them for every later surface. The sheet's
// labels must rasterise the same whatever was drawn before, or a simulated photograph of the
// sheet depends on which tests (or which of rfd make's steps) ran before it in the process.
// The reference picture is drawn in a fresh process (a death test re-executes the binary);
// this one draws a PDF first, as the CLI does.
TEST(PageText, APagesPictureIsTheSameWhateverWasDrawnBefore) {
    TempDir dir;
    const optics::Design design = bundled_design(1);
    const PrinterProfile printer = load_printer("epson_stylus_pro_4800");
    const MoireOptions options{default_pitch_range(design)};
    const MoireSheet sheet = moire_sheet(design, printer, options);
    constexpr double kPxPerMm = 12.0;
    const auto picture = [&] { return moire_page_codes(sheet, design, printer, 0, kPxPerMm); };
    // The child runs this body again up to EXPECT_EXIT: it keeps its parent's file name.
    constexpr const char* kFreshFile = "RFD_TEST_FRESH_PICTURE";
    if (!std::getenv(kFreshFile)) ::setenv(kFreshFile, (dir / "fresh.f32").c_str(), 1);
    const std::filesystem::path fresh_file = std::getenv(kFreshFile);
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    EXPECT_EXIT(
        {
            const Image fresh = picture();
            const std::span<const float> codes = fresh.plane(0);
            std::ofstream(fresh_file, std::ios::binary)
                .write(reinterpret_cast<const char*>(codes.data()), static_cast<std::streamsize>(codes.size_bytes()));
            std::filesystem::remove_all(dir.path());  // the child's own; exit runs no destructor
            std::exit(0);
        },
        ::testing::ExitedWithCode(0), "");
    ::unsetenv(kFreshFile);
    write_moire_pdf(dir / "calib.pdf", design, printer, options);
    const Image after_pdf_picture = picture();
    const std::span<const float> after_pdf = after_pdf_picture.plane(0);
    std::ifstream in(fresh_file, std::ios::binary);
    std::vector<float> fresh(after_pdf.size());
    in.read(reinterpret_cast<char*>(fresh.data()), static_cast<std::streamsize>(fresh.size() * sizeof(float)));
    ASSERT_TRUE(in) << "the fresh process wrote no picture";
    // The page is inked (grey edges: anti-aliased), and every pixel is the same.
    long long grey = 0, differing = 0;
    for (std::size_t k = 0; k < fresh.size(); ++k) {
        grey += fresh[k] > 0.05f && fresh[k] < 0.95f;
        differing += fresh[k] != after_pdf[k];
    }
    EXPECT_GT(grey, 1000);
    EXPECT_EQ(differing, 0);
}

TEST(Moire, BandsForEveryHypothesisOnPaperSizedPages) {
    TempDir dir;
    const optics::Design design = bundled_design(1);
    const PrinterProfile printer = load_printer("epson_stylus_pro_4800");
    MoireOptions options;
    options.x = parse_pitch_range("2.33:2.39:13", "--pitch");
    options.preview = dir / "calib.png";
    const auto bands = write_moire_pdf(dir / "calib.pdf", design, printer, options);
    // The first page's picture: the paper's shape, and ink on it (the bands' lines).
    const Page picture = read_page(dir / "calib.png");
    EXPECT_EQ(picture.height, kPagePreviewPixels);
    EXPECT_EQ(picture.width, static_cast<int>(std::lround(kPagePreviewPixels * printer.paper.width / printer.paper.height)));
    long long inked = 0;
    for (int y = 0; y < picture.height; ++y)
        for (int x = 0; x < picture.width; ++x) inked += picture.code(x, y) < 128;
    EXPECT_GT(inked, 1000);
    options.preview.clear();
    ASSERT_EQ(bands.size(), 26u);
    for (int k = 0; k < 13; ++k) {
        EXPECT_TRUE(bands[static_cast<std::size_t>(k)].along_x);
        EXPECT_NEAR(bands[static_cast<std::size_t>(k)].period, 2.33 + 0.005 * k, 1e-12);
        // Hexagonal rows lie pitch * sqrt(3) / 2 apart.
        EXPECT_FALSE(bands[static_cast<std::size_t>(13 + k)].along_x);
        EXPECT_NEAR(bands[static_cast<std::size_t>(13 + k)].period, (2.33 + 0.005 * k) * std::sqrt(3.0) / 2, 1e-12);
    }
    const std::string pdf = read_bytes(dir / "calib.pdf");
    EXPECT_NEAR(media_box_value(pdf, 2), 210.0 / 25.4 * 72.0, 1e-3);
    EXPECT_NEAR(media_box_value(pdf, 3), 297.0 / 25.4 * 72.0, 1e-3);
    // Bands within the printable area, in pages that say so in the PDF.
    int pages = 0;
    for (std::size_t at = pdf.find("/Type /Page"); at != std::string::npos; at = pdf.find("/Type /Page", at + 1))
        pages += pdf.compare(at, 12, "/Type /Pages") != 0;
    EXPECT_EQ(pages, bands.back().page + 1);
    for (const auto& band : bands) EXPECT_LE(band.top + 10.0, 297.0 - 3.0);

    // A rectangular array: rows default to the x range scaled by pitch_y / pitch_x.
    const optics::Design rect = bundled_design(2);
    options.x = parse_pitch_range("3.9:4.1:5", "--pitch");
    const auto rect_bands = write_moire_pdf(dir / "rect.pdf", rect, printer, options);
    EXPECT_NEAR(rect_bands[5].period, 3.9 * 4.8 / 4.0, 1e-12);
    EXPECT_NEAR(rect_bands[9].period, 4.1 * 4.8 / 4.0, 1e-12);
}

}  // namespace
}  // namespace rfd::print

