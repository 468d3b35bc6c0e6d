#include "print/moire.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>

#include <cairo-pdf.h>
#include <cairo.h>

#include "core/error.hpp"
#include "core/files.hpp"
#include "print/marks.hpp"
#include "print/pdf_file.hpp"
#include "core/text.hpp"
#include "optics/display.hpp"

namespace rfd::print {
namespace {

constexpr double kLabelColumn = 36.0;  // mm left of the bands for their labels
constexpr double kBandGap = 3.0;       // mm
constexpr double kMoireHeader = 16.0;  // mm for the instructions at the top of each page
constexpr double kMeasuringHeight = 25.0;  // mm, at least 4 rows of lenslets
constexpr double kMeasuringLineFraction = 0.5;
// A measuring band's lines: about this many spot widths (standard deviations) apart, so that
// the spot blurs them into a smooth profile every lenslet reads a phase from, but at least
// this many printer dots; the lenslets drift across the lines by this many fringes over the
// array, so that they read every phase...
constexpr double kMeasuringSpots = 5.0;
constexpr double kMeasuringDots = 12.0;
constexpr double kMeasuringFringes = 2.0;
// ...on top of a fifth of a period from one lenslet to the next: the moire then modulates the
// lenslets' brightness at a fifth of the lattice's frequency away from it, where the search
// for the lattice of lenslet images (calibrate/pitch.cpp) does not look.
constexpr double kBaseDrift = 0.2;
// A measuring band's slant: enough to cross this many lines over the band's length, but at
// most 3 deg: the slant mixes the band's short direction, which it measures poorly, into the
// scale it measures (by the slant's tangent).
constexpr double kSlantPeriods = 2.0;
constexpr double kMaxSlant = 0.0524;
constexpr double kMaxDrift = 0.45;
// An array laid whole on each band in turn (too small for the cross) has few lenslets. Its
// drift is a quarter period per lenslet: 0.45 puts the mirror alias (drift 1 - d) 1.3 % of
// Design II's pitch away, a quarter 6.9 %. A quarter repeats every four lenslets, so at turns
// of the array where the other direction's step is near a multiple of a quarter too its
// lenslets read few phases, and the scale reads a few times less precisely (the stated
// uncertainty says so); 0.35 and 1 / count were tried and read less precisely elsewhere
// (docs/results.md).
constexpr double kWholeArrayDrift = 0.25;
// Its lines are graded (MoireBand::graded): 30 lenslets reading sharp lines inform only near
// their edges, and one photograph pair scattered 0.035 % across the rows; graded ones inform
// at every phase, whatever part of the lenslet image a reading disc sees. Their period is about 5.3 whole spots (0.55 mm
// along Design II's rows, 0.77 mm across): there the whole lenslet's spot keeps half the
// cosine's depth, so its images are evenly lit enough for the lattice of them to be found.
// Over 16 hand-held placements (docs/results.md) 12 read within 0.0045 % and 4 were refused
// (the lattice not found). Shorter (0.28 mm, as the sharp lines were) the images' rims wash
// out against their middles: 14 read, 3 of them 0.013-0.016 % off; longer (1.2-1.5 mm) all
// 16 read, but up to 0.025 % off.
constexpr double kWholeArraySpot = 1.06;
// Graded lines are printed as this many codes a period (finer than the printer's dots).
constexpr int kGradedSamples = 64;
// ...in an image one sample tall and this long along the lines (mm): one tile spans any band,
// for PDF viewers that draw a repeated image tile by tile (poppler drew 1 mm tiles unturned).
constexpr double kGradedReach = 1000.0;
constexpr int kMaxMeasuringPeriods = 40;  // lines per lenslet: keeps the phase unambiguous over +-1 %
constexpr double kFallbackSpot = 0.02;    // mm, for designs the display simulator does not model

}  // namespace

const optics::Lattice& moire_lattice(const optics::Design& design) {
    const optics::Plane& pattern = design.pattern_plane();
    if (pattern.part)
        if (const auto* array = std::get_if<optics::LensletArrayPart>(&*pattern.part)) return array->lattice;
    for (const optics::Plane& plane : design.planes)
        if (plane.part)
            if (const auto* array = std::get_if<optics::LensletArrayPart>(&*plane.part)) return array->lattice;
    throw InputError(SourceLocation{design.file}, "design has no lenslet array to calibrate");
}

std::vector<double> PitchRange::values() const {
    RFD_CHECK(steps >= 2);
    std::vector<double> out;
    for (int k = 0; k < steps; ++k) out.push_back(from + (to - from) * k / (steps - 1));
    return out;
}

PitchRange parse_pitch_range(const std::string& text, const std::string& option) {
    const std::string expected = option + ": expected FROM:TO:STEPS in mm with 0 < FROM < TO and 2 <= STEPS <= 200, got '" + text + "'";
    const std::size_t a = text.find(':');
    const std::size_t b = a == std::string::npos ? a : text.find(':', a + 1);
    if (b == std::string::npos || text.find(':', b + 1) != std::string::npos) throw InputError(expected);
    PitchRange range;
    try {
        std::size_t used = 0;
        const std::string from = text.substr(0, a), to = text.substr(a + 1, b - a - 1), steps = text.substr(b + 1);
        range.from = std::stod(from, &used);
        if (used != from.size()) throw InputError(expected);
        range.to = std::stod(to, &used);
        if (used != to.size()) throw InputError(expected);
        const long long n = std::stoll(steps, &used);
        if (used != steps.size() || n < 2 || n > 200) throw InputError(expected);
        range.steps = static_cast<int>(n);
    } catch (const std::logic_error&) {  // stod/stoll: not a number, out of range
        throw InputError(expected);
    }
    if (!std::isfinite(range.from) || !std::isfinite(range.to) || !(range.from > 0.0) || !(range.from < range.to))
        throw InputError(expected);
    return range;
}

PitchRange default_pitch_range(const optics::Design& design) {
    constexpr double kRelativeSpread = 0.004;
    const double pitch = moire_lattice(design).pitch_x();
    return {pitch * (1.0 - kRelativeSpread), pitch * (1.0 + kRelativeSpread), 9};
}

Eigen::Vector2d MoireBand::normal() const {
    const double angle = (along_x ? 0.0 : 0.5 * std::numbers::pi) + slant_rad;
    return {std::cos(angle), std::sin(angle)};
}

bool MoireBand::inside(double x, double y) const {
    const auto in = [&](const std::array<double, 4>& r) {
        return x >= r[0] && x <= r[0] + r[2] && y >= r[1] && y <= r[1] + r[3];
    };
    return in({left, top, width, height}) && !(hole[2] > 0.0 && in(hole));
}

namespace {
// Across the band's lines from the centred one's middle, in periods.
double periods_across(const MoireBand& band, double x, double y) {
    return band.normal().dot(Eigen::Vector2d(x - (band.left + 0.5 * band.width), y - (band.top + 0.5 * band.height))) /
           band.period;
}
}  // namespace

bool MoireBand::inked(double x, double y) const {
    if (!inside(x, y)) return false;
    const double across = periods_across(*this, x, y);
    return std::abs(across - std::round(across)) <= 0.5 * line_fraction;
}

double MoireBand::ink(double x, double y) const {
    if (!graded) return inked(x, y) ? 1.0 : 0.0;
    if (!inside(x, y)) return 0.0;
    return 0.5 * (1.0 + std::cos(2.0 * std::numbers::pi * periods_across(*this, x, y)));
}

Eigen::Vector2d lenslet_spot(const optics::Design& design) {
    if (design.kind != optics::DesignKind::I && design.kind != optics::DesignKind::II)
        return Eigen::Vector2d::Constant(kFallbackSpot);
    const optics::DisplaySimulator simulator(design);
    optics::SimulationOptions options;
    options.model = optics::Model::Exact;
    options.rays_per_side = 16;
    const optics::RepeatedRays rays =
        simulator.trace_lenslet({{Eigen::Vector3d::UnitZ(), {1.0, 1.0, 1.0}, kSunRadius}}, options);
    Eigen::Vector2d sum = Eigen::Vector2d::Zero(), sum2 = sum;
    double weight = 0.0;
    for (const optics::LensletRay& ray : rays.rays) {
        sum += ray.reaching * ray.on_pattern;
        sum2 += ray.reaching * ray.on_pattern.cwiseProduct(ray.on_pattern);
        weight += ray.reaching;
    }
    if (!(weight > 0.0)) return Eigen::Vector2d::Constant(kFallbackSpot);
    const Eigen::Vector2d mean = sum / weight;
    return (sum2 / weight - mean.cwiseProduct(mean)).cwiseMax(0.0).cwiseSqrt();
}

double measuring_period(double spacing, int count, double spot, double dot, bool whole_array) {
    const double target = std::max(kMeasuringSpots * (whole_array ? kWholeArraySpot : 1.0) * spot, kMeasuringDots * dot);
    const int whole = std::clamp(static_cast<int>(std::floor(spacing / target)), 1, kMaxMeasuringPeriods);
    const double drift = whole_array ? kWholeArrayDrift : std::min(kMaxDrift, kBaseDrift + kMeasuringFringes / count);
    return spacing / (whole + drift);
}

namespace {

// The measuring block's size, and whether its bands cross under the array (moire_sheet).
struct MeasuringBlock {
    double band_width = 0.0, measuring_height = 0.0, block_height = 0.0, rows_width = 0.0, first = 0.0, last = 0.0;
    bool cross = false;
};
MeasuringBlock measuring_block(const optics::Lattice& lattice, const Paper& paper, const SheetMarks& marks) {
    MeasuringBlock b;
    const double band_left = paper.margin + kLabelColumn;
    b.band_width = std::min(2.0 * lattice.half_extent().x(), paper.width - paper.margin - band_left);
    b.measuring_height = std::max(kMeasuringHeight, 4.0 * lattice.pitch_y());
    b.first = paper.margin + kMoireHeader;
    b.last = paper.height - paper.margin - marks.strip;
    b.block_height = std::min(b.last - b.first, std::max(2.0 * b.measuring_height + kBandGap, 2.0 * lattice.half_extent().y()));
    b.rows_width = std::min(b.measuring_height, b.band_width);
    b.cross = b.band_width >= 3.0 * b.rows_width && b.block_height >= 3.0 * b.measuring_height;
    return b;
}

// A source that paints graded lines of `period` mm across x (MoireBand::ink, centred on x = 0)
// in printer codes: the transmittance runs as the cosine from bare film to full ink through
// the printer's tone curve (printer_value), sampled kGradedSamples times a period.
std::unique_ptr<cairo_pattern_t, decltype(&cairo_pattern_destroy)> graded_lines(const PrinterProfile& printer,
                                                                                double period) {
    const double ink = printer.ink_transmittance();
    std::vector<int> codes(kGradedSamples);
    for (int k = 0; k < kGradedSamples; ++k) {
        const double phase = (k + 0.5) / kGradedSamples - 0.5;  // sample k's middle; 0 on the line's centre
        const double covered = 0.5 * (1.0 + std::cos(2.0 * std::numbers::pi * phase));
        const double value = printer.printer_value(1.0 - covered * (1.0 - ink));
        codes[static_cast<std::size_t>(k)] = static_cast<int>(std::lround(255.0 * (1.0 - value)));
    }
    const CairoSurface row = code_row(codes);
    std::unique_ptr<cairo_pattern_t, decltype(&cairo_pattern_destroy)> pattern(
        cairo_pattern_create_for_surface(row.get()), &cairo_pattern_destroy);
    cairo_pattern_set_extend(pattern.get(), CAIRO_EXTEND_REPEAT);
    cairo_pattern_set_filter(pattern.get(), CAIRO_FILTER_NEAREST);
    cairo_matrix_t to_samples;  // pattern space: sample k spans [k, k + 1); x = 0 at kGradedSamples / 2
    cairo_matrix_init_translate(&to_samples, 0.5 * kGradedSamples, 0.0);
    cairo_matrix_scale(&to_samples, kGradedSamples / period, 1.0 / kGradedReach);
    cairo_pattern_set_matrix(pattern.get(), &to_samples);
    return pattern;
}

}  // namespace

bool lays_array_whole(const optics::Design& design, const Paper& paper) {
    return !measuring_block(moire_lattice(design), paper, sheet_marks(paper)).cross;
}

MoireSheet moire_sheet(const optics::Design& design, const PrinterProfile& printer, const MoireOptions& options) {
    const optics::Lattice& lattice = moire_lattice(design);
    const bool hex = lattice.kind() == optics::LatticeKind::Hexagonal;
    const double row_factor = hex ? std::sqrt(3.0) / 2.0 : 1.0;
    PitchRange y_range = options.y.value_or(options.x);
    if (!options.y && !hex) {
        const double scale = lattice.pitch_y() / lattice.pitch_x();
        y_range.from *= scale;
        y_range.to *= scale;
    }
    const Paper& paper = printer.paper;
    MoireSheet sheet;
    sheet.marks = sheet_marks(paper);
    const double band_left = paper.margin + kLabelColumn;
    const MeasuringBlock block = measuring_block(lattice, paper, sheet.marks);
    const double band_width = block.band_width, measuring_height = block.measuring_height;
    const double band_height = std::max({options.band_height, 4.0 * options.x.to, 4.0 * y_range.to * row_factor});
    const double first = block.first, last = block.last;
    if (band_width < 4.0 * options.x.to || first + measuring_height > last || first + band_height > last)
        throw InputError(SourceLocation{printer.file, 0, 0, "paper"},
                         "a calibration band (" + format_fixed(band_width, 1) + " x " +
                             format_fixed(std::max(band_height, measuring_height), 1) +
                             " mm) does not fit the printable area of " + paper.name + " paper");
    // The measuring block at the top of page 1, the array's size. The x band's lenslets must
    // span the array's width (the x scale), the rows band's its height (the row spacing), and
    // both keep off the array's edge (its outer lenslets lack neighbours): a cross, the x band
    // across the block's middle and the rows band down it, the square where they meet left
    // bare, as are the four corners. An array too small for a cross is laid whole on each of
    // two bands in turn, one above the other, each reaching a lenslet beyond the array on
    // every side so that its outer lenslets read lines too when it is laid by hand.
    double block_height = block.block_height;
    const double rows_width = block.rows_width;
    const bool cross = block.cross;
    sheet.whole_array = !cross;
    const Eigen::Vector2d spot = options.spot_mm.value_or(lenslet_spot(design));
    const double x_period = measuring_period(lattice.pitch_x(), lattice.count_x(), spot.x(), printer.dpi_x.dot_mm(), !cross);
    const double y_period = measuring_period(lattice.pitch_y(), lattice.count_y(), spot.y(), printer.dpi_y.dot_mm(), !cross);
    MoireBand x_measure{true, lattice.pitch_x(), x_period}, y_measure{false, lattice.pitch_y(), y_period};
    if (cross) {
        x_measure.top = first + 0.5 * (block_height - measuring_height);
        x_measure.left = band_left;
        x_measure.width = band_width;
        x_measure.height = measuring_height;
        y_measure.top = first;
        y_measure.left = band_left + 0.5 * (band_width - rows_width);
        y_measure.width = rows_width;
        y_measure.height = block_height;
        x_measure.hole = {y_measure.left, x_measure.top, y_measure.width, x_measure.height};
        y_measure.hole = x_measure.hole;
    } else {
        const double width = std::min(2.0 * (lattice.half_extent().x() + lattice.pitch_x()),
                                      paper.width - paper.margin - band_left);
        const double height = std::max(measuring_height, 2.0 * (lattice.half_extent().y() + lattice.pitch_y()));
        block_height = 2.0 * height + kBandGap;
        if (first + block_height > last)
            throw InputError(SourceLocation{printer.file, 0, 0, "paper"},
                             "the measuring bands (" + format_fixed(width, 1) + " x " + format_fixed(height, 1) +
                                 " mm each) do not fit the printable area of " + paper.name + " paper");
        for (MoireBand* band : {&x_measure, &y_measure}) {
            band->top = band == &x_measure ? first : first + height + kBandGap;
            band->left = band_left;
            band->width = width;
            band->height = height;
        }
    }
    for (MoireBand* band : {&x_measure, &y_measure}) {
        band->line_fraction = kMeasuringLineFraction;
        band->measuring = true;
        band->graded = !cross;
        // Slanted so that the lenslets of one column (x) or one row (rows) cross several
        // lines too, whatever the array's own small turn.
        const double length = band->along_x ? band->height : band->width;
        band->slant_rad = std::min(kMaxSlant, std::atan(kSlantPeriods * band->period / length));
    }
    sheet.measuring = {x_measure, y_measure};
    // Then the hypotheses, page by page.
    int page = 0;
    double top = first + block_height + kBandGap;
    const auto place = [&](MoireBand band) {
        if (top + band_height > last) ++page, top = first;
        band.page = page;
        band.top = top;
        band.left = band_left;
        band.width = band_width;
        band.height = band_height;
        top += band_height + kBandGap;
        return band;
    };
    for (const double p : options.x.values()) sheet.bands.push_back(place({true, p, p}));
    for (const double p : y_range.values()) sheet.bands.push_back(place({false, p, p * row_factor}));
    sheet.pages = page + 1;
    return sheet;
}

void draw_moire_page(cairo_t* cr, const MoireSheet& sheet, const optics::Design& design,
                     const PrinterProfile& printer, int page) {
    const optics::Lattice& lattice = moire_lattice(design);
    const bool hex = lattice.kind() == optics::LatticeKind::Hexagonal;
    const SheetMarks& marks = sheet.marks;
    const Paper& paper = printer.paper;
    cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_font_size(cr, 2.6);
    const std::string header[] = {
        "Pitch calibration (moire) - " + design.name + " - page " + std::to_string(page + 1) + " of " +
            std::to_string(sheet.pages),
        "Lay the array on a band, curved side up, its rows parallel to the band's long edge; the band whose",
        "fringes are widest or vanish (the band looks even) has the array's true pitch. x: spacing within a row,",
        "rows: spacing of the rows. Design: pitch " + format_fixed(lattice.pitch_x(), 4) + " mm, rows " +
            format_fixed(lattice.pitch_y(), 4) + " mm apart. " + printer.name + "."};
    for (std::size_t k = 0; k < std::size(header); ++k) {
        cairo_move_to(cr, paper.margin + marks.indent, paper.margin + 3.0 + 3.2 * static_cast<double>(k));
        cairo_show_text(cr, header[k].c_str());
    }
    draw_marks(cr, marks);
    std::vector<MoireBand> all = sheet.measuring;
    all.insert(all.end(), sheet.bands.begin(), sheet.bands.end());
    for (const MoireBand& band : all) {
        if (band.page != page) continue;
        // Label: the hypothesis, and which spacing it tests; or what a measuring band measures.
        cairo_set_font_size(cr, 2.8);
        const std::string name = band.measuring ? std::string(band.along_x ? "measure x" : "measure rows")
                                 : band.along_x ? "x " + format_fixed(band.pitch, 4) + " mm"
                                 : hex          ? "rows " + format_fixed(band.period, 4) + " mm"
                                                : "rows " + format_fixed(band.pitch, 4) + " mm";
        cairo_move_to(cr, paper.margin, band.top + 0.5 * band.height);
        cairo_show_text(cr, name.c_str());
        if (band.measuring) {
            cairo_set_font_size(cr, 2.0);
            cairo_move_to(cr, paper.margin, band.top + 0.5 * band.height + 3.0);
            cairo_show_text(cr, ("(lines " + format_fixed(band.period, 5) + " mm)").c_str());
            if (sheet.whole_array) {  // a photograph of the whole array on each band in turn
                cairo_move_to(cr, paper.margin, band.top + 0.5 * band.height + 5.5);
                cairo_show_text(cr, "(the whole array on it)");
            }
        } else if (!band.along_x && hex) {
            cairo_set_font_size(cr, 2.0);
            cairo_move_to(cr, paper.margin, band.top + 0.5 * band.height + 3.0);
            cairo_show_text(cr, ("(pitch " + format_fixed(band.pitch, 4) + " mm)").c_str());
        }
        // Lines of period `period`, a quarter period wide, one centred in the band
        // (MoireBand::inked says the same).
        cairo_save(cr);
        cairo_rectangle(cr, band.left, band.top, band.width, band.height);
        if (band.hole[2] > 0.0) {
            cairo_rectangle(cr, band.hole[0], band.hole[1], band.hole[2], band.hole[3]);
            cairo_set_fill_rule(cr, CAIRO_FILL_RULE_EVEN_ODD);
        }
        cairo_clip(cr);
        cairo_set_fill_rule(cr, CAIRO_FILL_RULE_WINDING);
        const double width = band.line_fraction * band.period;
        if (band.graded) {
            // One period of the cosine as exact printer codes (as the step wedge's patches:
            // code 255 is no ink), repeated across the lines in the frame turned to their normal.
            cairo_translate(cr, band.left + 0.5 * band.width, band.top + 0.5 * band.height);
            cairo_rotate(cr, std::atan2(band.normal().y(), band.normal().x()));
            cairo_set_source(cr, graded_lines(printer, band.period).get());
            cairo_paint(cr);
        } else if (band.slant_rad != 0.0) {
            // Slanted lines: drawn in a frame turned to the band's normal, about its centre.
            cairo_translate(cr, band.left + 0.5 * band.width, band.top + 0.5 * band.height);
            cairo_rotate(cr, std::atan2(band.normal().y(), band.normal().x()));
            const double reach = std::hypot(band.width, band.height);
            const int n = static_cast<int>(std::ceil(0.5 * reach / band.period)) + 1;
            for (int k = -n; k <= n; ++k) cairo_rectangle(cr, k * band.period - 0.5 * width, -reach, width, 2 * reach);
        } else if (band.along_x) {
            const double centre = band.left + 0.5 * band.width;
            const int n = static_cast<int>(std::ceil(0.5 * band.width / band.period)) + 1;
            for (int k = -n; k <= n; ++k)
                cairo_rectangle(cr, centre + k * band.period - 0.5 * width, band.top, width, band.height);
        } else {
            const double centre = band.top + 0.5 * band.height;
            const int n = static_cast<int>(std::ceil(0.5 * band.height / band.period)) + 1;
            for (int k = -n; k <= n; ++k)
                cairo_rectangle(cr, band.left, centre + k * band.period - 0.5 * width, band.width, width);
        }
        cairo_fill(cr);
        cairo_restore(cr);
    }
}

Image moire_page_codes(const MoireSheet& sheet, const optics::Design& design, const PrinterProfile& printer, int page,
                       double px_per_mm) {
    return page_codes(printer.paper.width, printer.paper.height, px_per_mm,
                      [&](cairo_t* cr) { draw_moire_page(cr, sheet, design, printer, page); });
}

std::vector<MoireBand> write_moire_pdf(const std::filesystem::path& out, const optics::Design& design,
                                       const PrinterProfile& printer, const MoireOptions& options) {
    const MoireSheet sheet = moire_sheet(design, printer, options);
    write_pages(out, printer.paper, sheet.pages, "calibration sheet",
                [&](cairo_t* cr, int page) { draw_moire_page(cr, sheet, design, printer, page); }, options.preview);
    return sheet.bands;
}

}  // namespace rfd::print
