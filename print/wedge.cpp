#include "print/wedge.hpp"

#include <cmath>
#include <memory>
#include <string>

#include <cairo.h>

#include "core/error.hpp"
#include "core/text.hpp"
#include "core/units.hpp"
#include "print/pdf_file.hpp"

namespace rfd::print {
namespace {

constexpr double kPatch = 16.0;   // mm, side of a patch
constexpr double kGap = 4.0;      // mm between patches, across
constexpr double kLabel = 10.0;   // mm below a patch for its label
constexpr double kWedgeHeader = 20.0;  // mm for the instructions at the top of each page

// One patch: a 1 x 1 image of `code`, drawn over the square without smoothing, the way
// sheets draw patterns.
void draw_patch(cairo_t* cr, int code, double left, double top) {
    const CairoSurface dot = code_row({code});
    cairo_save(cr);
    cairo_translate(cr, left, top);
    cairo_scale(cr, kPatch, kPatch);
    cairo_set_source_surface(cr, dot.get(), 0, 0);
    cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
    cairo_rectangle(cr, 0, 0, 1, 1);
    cairo_fill(cr);
    cairo_restore(cr);
    // A thin outline, so the bare-film patch has an edge.
    cairo_set_line_width(cr, 0.1);
    cairo_rectangle(cr, left, top, kPatch, kPatch);
    cairo_stroke(cr);
}

}  // namespace

std::vector<WedgePatch> wedge_patches(const PrinterProfile& printer, int steps) {
    if (steps < 2 || steps > 256) throw InputError("wedge steps: expected 2 to 256, got " + std::to_string(steps));
    std::vector<WedgePatch> patches;
    for (int k = 0; k < steps; ++k) {
        WedgePatch patch;
        patch.code = static_cast<int>(std::lround(255.0 * (1.0 - static_cast<double>(k) / (steps - 1))));
        patch.ink = 1.0 - patch.code / 255.0;
        patch.transmittance = printer.transmittance(patch.ink);
        patches.push_back(patch);
    }
    return patches;
}

WedgeSheet wedge_sheet(const PrinterProfile& printer, int steps) {
    WedgeSheet sheet;
    sheet.patches = wedge_patches(printer, steps);
    sheet.patch_size = kPatch;
    const Paper& paper = printer.paper;
    sheet.marks = sheet_marks(paper);
    const int columns = static_cast<int>(std::floor((paper.width - 2 * paper.margin + kGap) / (kPatch + kGap)));
    const int rows = static_cast<int>(
        std::floor((paper.height - 2 * paper.margin - kWedgeHeader - sheet.marks.strip) / (kPatch + kLabel)));
    if (columns < 1 || rows < 1)
        throw InputError(SourceLocation{printer.file, 0, 0, "paper"},
                         "a wedge patch (" + format_number(kPatch) + " mm and its label) does not fit the printable "
                         "area of " + paper.name + " paper");
    for (std::size_t k = 0; k < sheet.patches.size(); ++k) {
        const int slot = static_cast<int>(k);
        sheet.patches[k].page = slot / (columns * rows);
        sheet.patches[k].left = paper.margin + (slot % columns) * (kPatch + kGap);
        sheet.patches[k].top = paper.margin + kWedgeHeader + ((slot / columns) % rows) * (kPatch + kLabel);
    }
    sheet.pages = sheet.patches.back().page + 1;
    return sheet;
}

void draw_wedge_page(cairo_t* cr, const WedgeSheet& sheet, const PrinterProfile& printer, int page) {
    const Paper& paper = printer.paper;
    cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_font_size(cr, 2.6);
    const std::string header[] = {
        "Step wedge - " + printer.name + " - " + format_number(printer.dpi_x.value) + " x " +
            format_number(printer.dpi_y.value) + " dpi - page " + std::to_string(page + 1) + " of " +
            std::to_string(sheet.pages),
        "Print on your film at 100 %, colour management off, as you print patterns. Scan or photograph it",
        "with the four corner discs in view, then: rfd calibrate tone PRINTER SCAN (docs/usage.md). Under",
        "each patch: code, ink v, and the transmittance T the profile predicts (against bare film)."};
    for (std::size_t k = 0; k < std::size(header); ++k) {
        cairo_move_to(cr, paper.margin + sheet.marks.indent, paper.margin + 3.0 + 3.2 * static_cast<double>(k));
        cairo_show_text(cr, header[k].c_str());
    }
    draw_marks(cr, sheet.marks);
    for (const WedgePatch& patch : sheet.patches) {
        if (patch.page != page) continue;
        cairo_set_source_rgb(cr, 0, 0, 0);
        draw_patch(cr, patch.code, patch.left, patch.top);
        cairo_set_source_rgb(cr, 0, 0, 0);
        cairo_set_font_size(cr, 2.2);
        cairo_move_to(cr, patch.left, patch.top + kPatch + 2.8);
        cairo_show_text(cr, ("code " + std::to_string(patch.code)).c_str());
        cairo_move_to(cr, patch.left, patch.top + kPatch + 5.2);
        cairo_show_text(cr, ("v " + format_fixed(patch.ink, 3)).c_str());
        cairo_move_to(cr, patch.left, patch.top + kPatch + 7.6);
        cairo_show_text(cr, ("T " + format_fixed(patch.transmittance, 4)).c_str());
    }
}

Image wedge_page_codes(const WedgeSheet& sheet, const PrinterProfile& printer, int page, double px_per_mm) {
    return page_codes(printer.paper.width, printer.paper.height, px_per_mm,
                      [&](cairo_t* cr) { draw_wedge_page(cr, sheet, printer, page); });
}

std::vector<WedgePatch> write_wedge_pdf(const std::filesystem::path& out, const PrinterProfile& printer, int steps,
                                        const std::filesystem::path& preview) {
    const WedgeSheet sheet = wedge_sheet(printer, steps);
    write_pages(out, printer.paper, sheet.pages, "step wedge",
                [&](cairo_t* cr, int page) { draw_wedge_page(cr, sheet, printer, page); }, preview);
    return sheet.patches;
}

}  // namespace rfd::print
