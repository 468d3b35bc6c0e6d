#include "print/moire.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include <cairo-pdf.h>
#include <cairo.h>

#include "core/error.hpp"
#include "core/files.hpp"
#include "print/marks.hpp"
#include "print/pdf_file.hpp"
#include "core/text.hpp"

namespace rfd::print {
namespace {

constexpr double kLabelColumn = 36.0;  // mm left of the bands for their labels
constexpr double kBandGap = 3.0;       // mm
constexpr double kMoireHeader = 16.0;  // mm for the instructions at the top of each page
constexpr double kLineFraction = 0.25;  // a line's width, of its period

const optics::Lattice& array_lattice(const optics::Design& design) {
    const optics::Plane& pattern = design.pattern_plane();
    if (pattern.part)
        if (const auto* array = std::get_if<optics::LensletArrayPart>(&*pattern.part)) return array->lattice;
    for (const optics::Plane& plane : design.planes)
        if (plane.part)
            if (const auto* array = std::get_if<optics::LensletArrayPart>(&*plane.part)) return array->lattice;
    throw InputError(SourceLocation{design.file}, "design has no lenslet array to calibrate");
}

}  // namespace

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
    const double pitch = array_lattice(design).pitch_x();
    return {pitch * (1.0 - kRelativeSpread), pitch * (1.0 + kRelativeSpread), 9};
}

bool MoireBand::inked(double x, double y) const {
    if (x < left || x > left + width || y < top || y > top + height) return false;
    // Across the lines, from the centred one's middle, in periods.
    const double across = along_x ? (x - (left + 0.5 * width)) / period : (y - (top + 0.5 * height)) / period;
    return std::abs(across - std::round(across)) <= 0.5 * kLineFraction;
}

MoireSheet moire_sheet(const optics::Design& design, const PrinterProfile& printer, const MoireOptions& options) {
    const optics::Lattice& lattice = array_lattice(design);
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
    const double band_width = std::min(2.0 * lattice.half_extent().x(), paper.width - paper.margin - band_left);
    const double band_height = std::max({options.band_height, 4.0 * options.x.to, 4.0 * y_range.to * row_factor});
    const double usable = paper.height - 2 * paper.margin - kMoireHeader - sheet.marks.strip;
    const int per_page = static_cast<int>(std::floor((usable + kBandGap) / (band_height + kBandGap)));
    if (per_page < 1 || band_width < 4.0 * options.x.to)
        throw InputError(SourceLocation{printer.file, 0, 0, "paper"},
                         "a calibration band (" + format_fixed(band_width, 1) + " x " + format_fixed(band_height, 1) +
                             " mm) does not fit the printable area of " + paper.name + " paper");
    for (const double p : options.x.values()) sheet.bands.push_back({true, p, p, 0, 0.0});
    for (const double p : y_range.values()) sheet.bands.push_back({false, p, p * row_factor, 0, 0.0});
    for (std::size_t k = 0; k < sheet.bands.size(); ++k) {
        MoireBand& band = sheet.bands[k];
        band.page = static_cast<int>(k) / per_page;
        band.top = paper.margin + kMoireHeader + (static_cast<int>(k) % per_page) * (band_height + kBandGap);
        band.left = band_left;
        band.width = band_width;
        band.height = band_height;
    }
    sheet.pages = sheet.bands.back().page + 1;
    return sheet;
}

std::vector<MoireBand> write_moire_pdf(const std::filesystem::path& out, const optics::Design& design,
                                       const PrinterProfile& printer, const MoireOptions& options) {
    const optics::Lattice& lattice = array_lattice(design);
    const bool hex = lattice.kind() == optics::LatticeKind::Hexagonal;
    const MoireSheet sheet = moire_sheet(design, printer, options);
    const std::vector<MoireBand>& bands = sheet.bands;
    const SheetMarks& marks = sheet.marks;
    const Paper& paper = printer.paper;

    const int pages = sheet.pages;
    // One page, user units page-frame mm.
    const auto draw_page = [&](cairo_t* cr, int page) {
            cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
            cairo_set_source_rgb(cr, 0, 0, 0);
            cairo_set_font_size(cr, 2.6);
            const std::string header[] = {
                "Pitch calibration (moire) - " + design.name + " - page " + std::to_string(page + 1) + " of " +
                    std::to_string(pages),
                "Lay the array on a band, curved side up, its rows parallel to the band's long edge; the band whose",
                "fringes are widest or vanish (the band looks even) has the array's true pitch. x: spacing within a row,",
                "rows: spacing of the rows. Design: pitch " + format_fixed(lattice.pitch_x(), 4) + " mm, rows " +
                    format_fixed(lattice.pitch_y(), 4) + " mm apart. " + printer.name + "."};
            for (std::size_t k = 0; k < std::size(header); ++k) {
                cairo_move_to(cr, paper.margin + marks.indent, paper.margin + 3.0 + 3.2 * static_cast<double>(k));
                cairo_show_text(cr, header[k].c_str());
            }
            draw_marks(cr, marks);
            for (const MoireBand& band : bands) {
                if (band.page != page) continue;
                // Label: the hypothesis, and which spacing it tests.
                cairo_set_font_size(cr, 2.8);
                const std::string name = band.along_x ? "x " + format_fixed(band.pitch, 4) + " mm"
                                         : hex ? "rows " + format_fixed(band.period, 4) + " mm"
                                               : "rows " + format_fixed(band.pitch, 4) + " mm";
                cairo_move_to(cr, paper.margin, band.top + 0.5 * band.height);
                cairo_show_text(cr, name.c_str());
                if (!band.along_x && hex) {
                    cairo_set_font_size(cr, 2.0);
                    cairo_move_to(cr, paper.margin, band.top + 0.5 * band.height + 3.0);
                    cairo_show_text(cr, ("(pitch " + format_fixed(band.pitch, 4) + " mm)").c_str());
                }
                // Lines of period `period`, a quarter period wide, one centred in the band
                // (MoireBand::inked says the same).
                cairo_save(cr);
                cairo_rectangle(cr, band.left, band.top, band.width, band.height);
                cairo_clip(cr);
                const double width = kLineFraction * band.period;
                if (band.along_x) {
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
    };
    write_pages(out, paper, pages, "calibration sheet", draw_page, options.preview);
    return bands;
}

}  // namespace rfd::print
