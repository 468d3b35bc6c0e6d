// Predicted display output against the software relighting of the same field
// (predict/compare.hpp), as numbers: Design II shows its field at >= 30 dB inside its field
// of view; Design I, whose partial images slide on the diffuser as the light moves, only near
// its axis; a pattern shifted on the sheet loses many dB (the comparison can fail); the SIG08
// letters of the thesis's Design II demonstration each appear under their own light and
// not under the others'.

#include <algorithm>
#include <cmath>
#include <numeric>

#include <Eigen/Dense>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/sphere.hpp"
#include "core/units.hpp"
#include "optics/display.hpp"
#include "predict/compare.hpp"
#include "patterns/encode.hpp"
#include "patterns/procedural.hpp"
#include "predict/summaries.hpp"
#include "predict/verdict.hpp"
#include "print/printer.hpp"
#include "tests/support/displays.hpp"
#include "tests/support/error_of.hpp"

namespace rfd::predict {
namespace {

using namespace rfd::patterns;
using rfd::testing::design2;
using rfd::testing::pearson;
using rfd::testing::small_design1;

using ::testing::HasSubstr;
using rfd::testing::error_of;

// A field encoded and "printed" in memory: the encoder, and its pattern through the tone
// mapping as the transparency the simulator sees (optionally shifted on the sheet by
// `shift_dots` dots to the right, to make a wrong print).
struct Printed {
    std::unique_ptr<Encoder> encoder;
    std::unique_ptr<optics::RasterTransparency> transparency;
    print::ToneMap tone;
};

// The encoder's model is the one `rfd pattern encode` picks by default (auto: exact for
// both presets at their 2880 x 1440 dpi).
Printed print_field(const optics::Design& design, const relight::ReflectanceField& field, EncodeOptions options,
                    int shift_dots = 0) {
    Printed p;
    const PatternGeometry geometry = pattern_geometry(design, design.printer.dpi_x, design.printer.dpi_y);
    options.model = optics::resolve(optics::ModelChoice::Auto, optics::DesignOptics(design), {geometry.dot_x, geometry.dot_y}).model;
    p.encoder = std::make_unique<Encoder>(design, field, geometry, options);
    p.tone.printer = print::load_printer("epson_stylus_pro_4800");
    p.tone.white = p.encoder->white();
    p.tone.sheets = 1;
    const std::size_t channels = static_cast<std::size_t>(p.encoder->channels());
    const std::size_t row = static_cast<std::size_t>(geometry.width) * channels;
    std::vector<float> values(geometry.dot_count() * channels, static_cast<float>(p.tone.stack_transmittance(0.0)));
    std::vector<float> buffer(row);
    for (int py = 0; py < geometry.height; ++py) {
        p.encoder->render_row(py, buffer);
        for (int px = 0; px < geometry.width; ++px) {
            const int to = px + shift_dots;
            if (to < 0 || to >= geometry.width) continue;
            for (std::size_t c = 0; c < channels; ++c)
                values[static_cast<std::size_t>(py) * row + static_cast<std::size_t>(to) * channels + c] =
                    static_cast<float>(p.tone.stack_transmittance(buffer[static_cast<std::size_t>(px) * channels + c]));
        }
    }
    p.transparency = std::make_unique<optics::RasterTransparency>(geometry.width, geometry.height,
                                                                  static_cast<int>(channels), geometry.dot_x,
                                                                  geometry.dot_y, std::move(values));
    return p;
}

// A field with content at every direction of Design II's range: the diamonds of thesis
// figure 8.15 on a 5 x 5 grid of directions reaching 14 degrees (the range's corners are at
// 16.6), blended by the Delaunay interpolation.
relight::ReflectanceField diamonds_field() {
    ProceduralOptions options;
    options.kind = ProceduralKind::Diamonds;
    options.spread_deg = 14.0;
    options.width = 48;
    options.height = 40;
    return procedural_field(options);
}

// The simulation the comparisons use: 32 x 32 rays per lenslet (the PSNR of Design II's
// macro-pixel cores converges to within a dB there; 8 x 8 rays alias against the pixels),
// 16 pixels per pitch.
optics::SimulationOptions converged() {
    optics::SimulationOptions options;
    options.rays_per_side = 32;
    options.pixels_per_pitch = 16.0;
    return options;
}


TEST(CompareImages, KnownAnswers) {
    Image reference(3, 2, 3), prediction(3, 2, 3);
    for (std::size_t k = 0; k < reference.samples().size(); ++k) {
        reference.samples()[k] = 0.1f * static_cast<float>(k % 7);
        prediction.samples()[k] = 0.5f * reference.samples()[k];
    }
    const ImageComparison c = compare_images(prediction, reference);
    double mse = 0.0;
    for (float q : reference.samples()) mse += 0.25 * q * q;
    mse /= static_cast<double>(reference.samples().size());
    EXPECT_NEAR(c.peak, 0.6, 1e-6);
    EXPECT_NEAR(c.mse, mse, 1e-9);
    EXPECT_NEAR(c.psnr_db, 10.0 * std::log10(0.36 / mse), 1e-6);
    EXPECT_NEAR(c.fitted_gain, 2.0, 1e-6);  // P = Q / 2: a gain of 2 restores it
    EXPECT_GT(c.psnr_fitted_db, 100.0);
    EXPECT_FLOAT_EQ(c.error.at(2, 1, 2), prediction.at(2, 1, 2) - reference.at(2, 1, 2));
    EXPECT_TRUE(std::isinf(compare_images(reference, reference).psnr_db));
}

TEST(EncodeOptionsOf, RoundTripsTheEncodersAttributes) {
    const optics::Design design = design2();
    EncodeOptions options;
    options.model = optics::Model::Exact;
    options.exact_table_nodes = 9;
    options.interpolation = relight::Interpolation::Nearest;
    options.fit = ImageFit::Contain;
    options.mapping = {12.5, -30.0, 1.25};
    options.window = relight::parse_region("120,40,800,600", "--region");
    options.window.scale = 0.3;
    const PatternGeometry geometry = pattern_geometry(design, Dpi{360}, Dpi{360});
    const Encoder encoder(design, diamonds_field(), geometry, options);
    PatternFileInfo info;
    info.attributes = encoder.attributes();
    const EncodeOptions read = encode_options_of(info, "p.exr");
    EXPECT_EQ(read.model, options.model);
    EXPECT_EQ(read.interpolation, options.interpolation);
    EXPECT_EQ(read.fit, options.fit);
    EXPECT_DOUBLE_EQ(read.mapping.tilt_deg, 12.5);
    EXPECT_DOUBLE_EQ(read.mapping.turn_deg, -30.0);
    EXPECT_DOUBLE_EQ(read.mapping.angle_scale, 1.25);
    EXPECT_EQ(read.field_name, encoder.options().field_name);
    EXPECT_EQ(read.window.x, 120);
    EXPECT_EQ(read.window.y, 40);
    EXPECT_EQ(read.window.width, 800);
    EXPECT_EQ(read.window.height, 600);
    EXPECT_EQ(read.window.scale, 0.3);
    EXPECT_EQ(encode_options_of(PatternFileInfo{}, "old.exr").model, optics::Model::Paraxial);

    // Patterns written before the two were recorded: the encoder's defaults.
    PatternFileInfo older = info;
    older.attributes.erase("interpolation");
    older.attributes.erase("fit");
    EXPECT_EQ(encode_options_of(older, "p.exr").interpolation, relight::Interpolation::Delaunay);
    EXPECT_EQ(encode_options_of(older, "p.exr").fit, ImageFit::Cover);

    info.attributes["interpolation"] = "cubic";
    EXPECT_THAT(error_of([&] { encode_options_of(info, "p.exr"); }),
                HasSubstr("p.exr: rfd:interpolation: expected 'delaunay', 'solid-angle' or 'nearest', got 'cubic'"));
    info.attributes["interpolation"] = "nearest";
    info.attributes["tilt_deg"] = "4x";
    EXPECT_THAT(error_of([&] { encode_options_of(info, "p.exr"); }), HasSubstr("rfd:tilt_deg: expected a number"));
}

// Design II's corrective pair images A onto the diffuser at 1.157x (`rfd design show`):
// neighbours reach (1.157 - 1)/2 of a pitch into a cell from each side, leaving a core of
// 2 - 1.157 = 0.843 of its width. Design I has no such imaging: whole cells.
TEST(MacroPixelCore, FromTheCorrectivePairsMagnification) {
    const MacroPixelCore two = macro_pixel_core(optics::DesignOptics(design2()));
    EXPECT_NEAR(two.magnification, 1.157, 0.001);
    EXPECT_NEAR(two.fraction, 2.0 - two.magnification, 1e-12);
    const MacroPixelCore one = macro_pixel_core(optics::DesignOptics(small_design1(4, 4)));
    EXPECT_EQ(one.fraction, 1.0);
    EXPECT_EQ(one.magnification, 1.0);
}

// The whole cell is DisplaySimulator::per_lenslet; a core of a field that is uniform
// within each cell reads the cell's value; side_by_side lays the panels out as documented.
TEST(PerLensletCore, AgreesWithPerLensletAndReadsCellValues) {
    const optics::Design design = design2();
    const optics::DisplaySimulator simulator(design);
    const optics::Lattice& lattice = simulator.optics().lattice();
    optics::DiffuserImage image;
    image.pixel_mm = 0.25;
    image.image = Image(110, 100, 3);
    image.first_pixel = Eigen::Vector2d(-0.5 * 109 * image.pixel_mm, 0.5 * 99 * image.pixel_mm);
    for (int y = 0; y < image.image.height(); ++y)
        for (int x = 0; x < image.image.width(); ++x) {
            const optics::CellIndex cell = lattice.cell_at(image.pixel_centre(x, y));
            for (int c = 0; c < 3; ++c)
                image.image.at(x, y, c) = static_cast<float>(cell.i + 10 * cell.j + 100 * c + (x % 3) * 0.001);
        }
    EXPECT_EQ(per_lenslet_core(lattice, image, 1.0), simulator.per_lenslet(image));
    const Image core = per_lenslet_core(lattice, image, 0.5);
    for (int j = 0; j < lattice.count_y(); ++j)
        for (int i = 0; i < lattice.count_x(); ++i)
            EXPECT_NEAR(core.at(i, lattice.count_y() - 1 - j, 2), i + 10 * j + 200, 0.002) << i << ", " << j;

    DirectionComparison r;
    r.prediction = Image(2, 1, 3, 0.5f);
    r.reference = Image(2, 1, 3, 2.0f);
    r.comparison = compare_images(r.prediction, r.reference);
    const Image panels = side_by_side(r, 4, 4.0);
    EXPECT_EQ(panels.width(), 3 * 8 + 2 * 4);
    EXPECT_EQ(panels.height(), 4);
    EXPECT_FLOAT_EQ(panels.at(0, 0, 0), 0.25f);          // prediction / peak
    EXPECT_FLOAT_EQ(panels.at(8, 0, 0), 0.5f);           // the gap
    EXPECT_FLOAT_EQ(panels.at(12, 3, 1), 1.0f);          // reference / peak
    EXPECT_FLOAT_EQ(panels.at(31, 0, 2), 4.0f * 0.75f);  // |error| x 4 / peak
}

TEST(DisplayComparison, SweepSpreadsOverTheDisplaysRange) {
    const optics::Design design = design2();
    EncodeOptions options;
    options.mapping.tilt_deg = 20.0;
    const Printed p = print_field(design, diamonds_field(), options);
    const optics::DisplaySimulator simulator(design);
    const DisplayComparison comparison(simulator, *p.transparency, *p.encoder, p.tone);
    const std::vector<Eigen::Vector3d> sweep = comparison.sweep(12);
    ASSERT_EQ(sweep.size(), 12u);
    // The first light lies on the display's axis: the field direction the tilt maps it to.
    EXPECT_NEAR(angle_between(sweep[0], options.mapping.field_direction(Eigen::Vector3d::UnitZ())), 0.0, 1e-12);
    double largest = 0.0;
    for (const auto& v : sweep) largest = std::max(largest, angle_between(v, sweep[0]));
    EXPECT_NEAR(largest, p.encoder->display_range().max_angle_rad, 1e-9);
    EXPECT_EQ(comparison.sweep(12), sweep);  // deterministic
}

// Issue 5's accuracy target. Where no light of a lenslet reaches its neighbour's pattern
// cell and within 12 degrees of the axis, Design II shows the field it was encoded from at
// >= 30 dB per macro-pixel core, on the scale of its own clear-print response (measured
// 38-58 dB). Further out its spherical lenslets blur: the exact spot on the pattern grows
// from 85 um RMS on the axis to 784 um at half the field of view (`rfd design show`), a
// blur of about 4 degrees of light direction, and the figure falls (18 dB at 14 degrees
// along a diagonal in tests/cli/simulate_compare.cmake); paraxial optics, free of that
// blur, keep >= 30 dB wherever the exact bundle is crosstalk-free, so the loss is the
// lenses', not the comparison's. Between crosstalk and wrap-over (the rest of the field of
// view) part of each spot reads the neighbour's pattern: measured 18-22 dB, asserted < 30.
TEST(DisplayComparison, DesignTwoInsideItsFieldOfViewIsAtLeast30dB) {
    const optics::Design design = design2();
    const Printed p = print_field(design, diamonds_field(), EncodeOptions{});
    const optics::DisplaySimulator simulator(design);
    const DisplayComparison comparison(simulator, *p.transparency, *p.encoder, p.tone);
    optics::SimulationOptions paraxial = converged();
    paraxial.model = optics::Model::Paraxial;
    int sharp = 0, crosstalk = 0, outside = 0;
    for (const Eigen::Vector3d& v : comparison.sweep(20)) {
        const DirectionComparison r = comparison.compare(v, converged());
        SCOPED_TRACE("display angle " + std::to_string(r.display_angle_deg));
        // The scale's mean is the light into the lenslets times the optics' efficiency.
        EXPECT_GT(r.efficiency, 0.5);
        EXPECT_LE(r.efficiency, 1.0);
        if (r.crosstalk_free) {
            if (r.display_angle_deg <= 12.0) {
                ++sharp;
                EXPECT_GE(r.comparison.psnr_db, 30.0);
            }
            EXPECT_GE(comparison.compare(v, paraxial).comparison.psnr_db, 30.0);
        } else if (r.inside_field_of_view) {
            ++crosstalk;
            EXPECT_LT(r.comparison.psnr_db, 30.0);
        } else {
            ++outside;
        }
    }
    EXPECT_GE(sharp, 6);
    EXPECT_GE(crosstalk, 1);
    EXPECT_GE(outside, 1);  // the sweep reaches past the cell's flat sides
}

// A wrong print must show: the same pattern shifted by a quarter lenslet on the sheet
// shows other directions' values in every lenslet.
TEST(DisplayComparison, AShiftedPatternLosesManyDecibels) {
    const optics::Design design = design2();
    const relight::ReflectanceField field = diamonds_field();
    const Printed right = print_field(design, field, EncodeOptions{});
    const int quarter = static_cast<int>(std::lround(0.25 * 4.0 / right.encoder->geometry().dot_x));
    const Printed wrong = print_field(design, field, EncodeOptions{}, quarter);
    const optics::DisplaySimulator simulator(design);
    const DisplayComparison good(simulator, *right.transparency, *right.encoder, right.tone);
    const DisplayComparison bad(simulator, *wrong.transparency, *wrong.encoder, wrong.tone);
    int checked = 0;
    for (const Eigen::Vector3d& v : good.sweep(5)) {
        const DirectionComparison a = good.compare(v, converged()), b = bad.compare(v, converged());
        if (!a.crosstalk_free) continue;
        ++checked;
        EXPECT_LT(b.comparison.psnr_db, a.comparison.psnr_db - 10.0) << "display angle " << a.display_angle_deg;
    }
    EXPECT_GE(checked, 2);  // of the 5-sweep, the axis and one more are crosstalk-free (measured: 2)
}

// A field that is the same at every point and varies smoothly with the light: what a
// display shows of it cannot depend on where a lenslet's light lands on the diffuser.
relight::ReflectanceField uniform_field() {
    relight::ReflectanceField field;
    for (const Eigen::Vector3d& d : fibonacci_hemisphere(300)) {
        field.directions.push_back(d);
        const float value = static_cast<float>(0.2 + 0.6 * d.z() * (0.75 + 0.25 * d.x()));
        field.images.emplace_back(8, 8, 3, value);
    }
    return field;
}

// Design I has no corrective pair: a lenslet's partial image lands on the diffuser shifted
// by its distance behind the pattern times the light's slope (0.7 mm of a 2.36 mm pitch at
// 8 degrees, tests/test_display.cpp), and spreads over its neighbours' cells even on the
// axis (its spot on the pattern is 212 um RMS, `rfd design show`). With a spatially uniform
// field that mixing is invisible: the comparison must then find the display right (>= 30
// dB wherever it is crosstalk-free), so what it finds on structured fields is the design's.
TEST(DisplayComparison, DesignOneShowsAUniformFieldAtLeast30dB) {
    const optics::Design design = small_design1(6, 6);
    const Printed p = print_field(design, uniform_field(), EncodeOptions{});
    const optics::DisplaySimulator simulator(design);
    const DisplayComparison comparison(simulator, *p.transparency, *p.encoder, p.tone);
    // The axis and 6 degrees along the flat and the corner directions of the hexagonal cell,
    // where crosstalk_free's bundle (16 rays a side) finds no ray crossing. (The first light
    // crosses from 5.5 and 6.1 degrees there, through the lenslets' corners: `rfd design
    // show`.)
    for (const Eigen::Vector3d& d : {Eigen::Vector3d(Eigen::Vector3d::UnitZ()),
                                     optics::incident_direction(degrees_to_radians(6.0), 0.0),
                                     optics::incident_direction(degrees_to_radians(6.0), 0.5 * kPi)}) {
        const DirectionComparison r = comparison.compare(p.encoder->options().mapping.field_direction(d), converged());
        EXPECT_TRUE(r.crosstalk_free);
        EXPECT_GE(r.comparison.psnr_db, 30.0) << "display angle " << r.display_angle_deg;
    }
}

// Design I's figure on a structured field (the diamonds at 10 x 10 lenslets): measured 24.5
// dB on the axis; asserted >= 20 dB (a regression bound), and at least 6 dB below Design
// II's on the same field and light, which holds each partial image on its macro-pixel.
TEST(DisplayComparison, DesignOneLosesToDesignTwoOnStructuredFields) {
    const relight::ReflectanceField field = diamonds_field();
    const optics::Design one = small_design1(10, 10), two = design2();
    const Printed p1 = print_field(one, field, EncodeOptions{}), p2 = print_field(two, field, EncodeOptions{});
    const optics::DisplaySimulator s1(one), s2(two);
    const DisplayComparison c1(s1, *p1.transparency, *p1.encoder, p1.tone), c2(s2, *p2.transparency, *p2.encoder, p2.tone);
    const Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
    const DirectionComparison r1 = c1.compare(axis, converged()), r2 = c2.compare(axis, converged());
    EXPECT_GE(r1.comparison.psnr_db, 20.0);
    EXPECT_LT(r1.comparison.psnr_db, r2.comparison.psnr_db - 6.0);
}

// The thesis's SIG08 letters on Design II, encoded with nearest interpolation as the demo
// does, printed in memory and ready to compare. Not movable: the comparison keeps the
// simulator and the print by reference.
struct Sig08Display {
    std::string text = "SIG08";
    optics::Design design = design2();
    relight::ReflectanceField field = procedural_field(ProceduralOptions{.text = text, .width = 48, .height = 40});
    Printed p = print_field(design, field, EncodeOptions{.interpolation = relight::Interpolation::Nearest});
    optics::DisplaySimulator simulator{design};
    DisplayComparison comparison{simulator, *p.transparency, *p.encoder, p.tone};
};

// The thesis's Design II demonstration: "SIG08", one letter per light direction along the
// horizontal arc (5 degrees apart), encoded with nearest interpolation as the demo does.
// At 6 x 5 lenslets the letters' pictures overlap by shape and colour (S and 8 correlate
// 0.68, S and 0 0.57, G and 8 0.55), so "the others do not show" cannot mean a fixed low
// correlation. It means: under each letter's light the predicted display correlates with
// that letter's picture (> 0.99; measured 1.000), with every other letter no more than the
// two pictures share (+ 0.02), and fitted as a mixture of all five pictures it holds less
// than 3 % of any other letter (measured <= 1.7 %).
TEST(DisplayComparison, Sig08LettersAppearEachUnderItsOwnLightOnly) {
    const Sig08Display sig08;
    const relight::ReflectanceField& field = sig08.field;
    const DisplayComparison& comparison = sig08.comparison;
    const std::size_t n = sig08.text.size();
    std::vector<Image> pictures;
    for (std::size_t k = 0; k < n; ++k) pictures.push_back(comparison.transmittance(field.directions[k]));
    Eigen::MatrixXd basis(static_cast<Eigen::Index>(pictures[0].samples().size()), static_cast<Eigen::Index>(n));
    for (std::size_t k = 0; k < n; ++k)
        for (std::size_t i = 0; i < pictures[k].samples().size(); ++i)
            basis(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) = pictures[k].samples()[i];
    for (std::size_t k = 0; k < n; ++k) {
        const DirectionComparison r = comparison.compare(field.directions[k], converged());
        SCOPED_TRACE(std::string("letter ") + sig08.text[k]);
        EXPECT_TRUE(r.crosstalk_free);
        std::vector<double> correlation(n);
        for (std::size_t j = 0; j < n; ++j) correlation[j] = pearson(r.prediction, pictures[j]);
        EXPECT_GT(correlation[k], 0.99);
        for (std::size_t j = 0; j < n; ++j) {
            if (j == k) continue;
            // No more of letter j than letter k itself shares with it.
            EXPECT_LT(correlation[j], pearson(pictures[k], pictures[j]) + 0.02) << "letter " << sig08.text[j];
        }
        Eigen::VectorXd shown(basis.rows());
        for (std::size_t i = 0; i < r.prediction.samples().size(); ++i)
            shown(static_cast<Eigen::Index>(i)) = r.prediction.samples()[i];
        const Eigen::VectorXd mixture = basis.colPivHouseholderQr().solve(shown);
        for (std::size_t j = 0; j < n; ++j) {
            if (j == k) continue;
            EXPECT_LT(std::abs(mixture(static_cast<Eigen::Index>(j))), 0.03 * mixture(static_cast<Eigen::Index>(k)))
                << "letter " << sig08.text[j] << " correlation " << correlation[j];
        }
    }
}

// The one PSNR of a display against its field (predict/summaries.hpp) on the demo's SIG08
// project: over a sweep, directions whose reference is dark (between and beyond the
// letters) read what the display shows there, not -60 dB for a faint residue against
// their own faint peak; and the summary's mean over the field of view is the verdict's.
TEST(CompareSummary, Sig08DarkDirectionsStayMeaningfulAndTheSummaryAgreesWithTheVerdict) {
    const Sig08Display sig08;
    const DisplayComparison& comparison = sig08.comparison;
    optics::SimulationOptions simulation = converged();
    simulation.rays_per_side = 16;
    std::vector<DirectionComparison> results;
    std::vector<std::string> images;
    for (const Eigen::Vector3d& v : comparison.sweep(9)) {
        results.push_back(comparison.compare(v, simulation));
        images.push_back("light_" + std::to_string(images.size()) + ".png");
    }
    const CompareSummary summary = summarise_comparison(results, images);
    VerdictInputs inputs;
    int dark = 0, checked = 0;
    for (const CompareDirection& d : summary.directions) {
        inputs.directions.push_back({d.display_angle_deg, d.inside_fov, d.crosstalk_free, d.mse, d.peak});
        if (!d.inside_fov) continue;
        ++checked;
        ASSERT_TRUE(d.psnr_db) << d.image;
        EXPECT_GE(*d.psnr_db, 0.0) << d.image;
        EXPECT_LE(*d.psnr_db, 100.0) << d.image;
        if (d.peak < 0.1 * summary.field_peak) {
            ++dark;
            // The same residue against its own faint peak: 20 log10(field peak / peak) lower
            // (measured: a letter's crosstalk reads 16 dB here, -23 dB against its own peak).
            if (d.psnr_own_peak_db && *d.psnr_db < 100.0) {
                EXPECT_NEAR(*d.psnr_db - *d.psnr_own_peak_db, 20.0 * std::log10(summary.field_peak / d.peak), 1e-6)
                    << d.image;
            }
        }
    }
    EXPECT_GE(checked, 4);
    EXPECT_GE(dark, 1);  // the sweep does meet directions where the field is dark
    const Verdict verdict = judge(inputs);
    ASSERT_TRUE(summary.in_fov.mean_psnr_db && verdict.psnr_mean_in_fov_db);
    EXPECT_NEAR(*summary.in_fov.mean_psnr_db, *verdict.psnr_mean_in_fov_db, 1e-9);
    EXPECT_NEAR(*summary.in_fov.min_psnr_db, *verdict.psnr_min_in_fov_db, 1e-9);
    EXPECT_EQ(summary.in_fov.count, verdict.directions_in_fov);
}

TEST(AccuracySweep, ExactAtTheReferenceRaysIsTheReference) {
    const optics::Design design = design2();
    const Printed p = print_field(design, diamonds_field(), EncodeOptions{});
    const optics::DisplaySimulator simulator(design);
    const std::vector<Eigen::Vector3d> directions = {optics::incident_direction(0.0, 0.0),
                                                     optics::incident_direction(degrees_to_radians(8.0), 0.5)};
    const auto points = accuracy_sweep(simulator, *p.transparency, directions,
                                       {{"paraxial", optics::Model::Paraxial}, {"exact", optics::Model::Exact}}, {2, 8}, 8,
                                       optics::SimulationOptions{});
    ASSERT_EQ(points.size(), 4u);
    EXPECT_EQ(points[3].label, "exact");
    EXPECT_EQ(points[3].rays_per_side, 8);
    EXPECT_EQ(points[3].mse, 0.0);  // the same simulation as the reference, bit for bit
    EXPECT_EQ(points[3].rays, 2u * 30u * 64u);
    for (int k = 0; k < 3; ++k) {
        EXPECT_GT(points[static_cast<std::size_t>(k)].mse, 0.0);
        EXPECT_TRUE(std::isfinite(points[static_cast<std::size_t>(k)].psnr_db));
        EXPECT_EQ(points[static_cast<std::size_t>(k)].psnr_per_direction_db.size(), 2u);
    }
    EXPECT_LT(points[0].psnr_db, points[1].psnr_db);  // two rays per side are worse than eight
}

}  // namespace
}  // namespace rfd::predict
