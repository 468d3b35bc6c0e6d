#include "print/layout.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <cairo.h>

#include "core/error.hpp"
#include "optics/analysis.hpp"
#include "core/text.hpp"

namespace rfd::print {
namespace {

constexpr double kMarkLine = 0.1;       // mm, crop marks
constexpr double kRulerLine = 0.08;     // mm
constexpr double kCropGap = 1.0;        // mm between the pattern and a crop mark
constexpr double kCropLength = 4.5;     // mm
constexpr double kLabelFont = 2.4;      // mm, the label's font size
constexpr double kRulerFont = 1.8;      // mm

// The lattice whose corner lenslets carry markers, if the design has one.
std::optional<optics::Lattice> marker_lattice(const optics::Design& design) {
    switch (design.kind) {
        case optics::DesignKind::I:
        case optics::DesignKind::II:
            return optics::DesignOptics(design).lattice();
        case optics::DesignKind::III: {
            const optics::Plane& plane = design.pattern_plane();
            if (plane.part)
                if (const auto* array = std::get_if<optics::LensletArrayPart>(&*plane.part))
                    return array->lattice;
            return std::nullopt;
        }
        case optics::DesignKind::IV:
            return std::nullopt;
    }
    return std::nullopt;
}

std::vector<std::string> label_lines(const optics::Design& design, const PrinterProfile& printer,
                                     const SheetInfo& info) {
    std::string sheet;
    if (info.sheets == 1)
        sheet = "single sheet";
    else
        sheet = info.mirror ? "sheet 2 of 2: back, mirrored" : "sheet 1 of 2: front";
    return {design.name + "  -  pattern " + info.pattern_name,
            printer.name + ", " + format_number(printer.dpi_x.value) + " x " +
                format_number(printer.dpi_y.value) + " dpi, brightness " +
                format_number(info.brightness) + ", " + sheet};
}

void show_text_at(cairo_t* cr, const std::string& text, double x, double y, double size,
                  double centre_x = std::nan("")) {
    cairo_set_font_size(cr, size);
    if (std::isfinite(centre_x)) {
        cairo_text_extents_t extents;
        cairo_text_extents(cr, text.c_str(), &extents);
        x = centre_x - (extents.x_bearing + 0.5 * extents.width);
    }
    cairo_move_to(cr, x, y);
    cairo_show_text(cr, text.c_str());
}

}  // namespace

Eigen::Vector2d SheetLayout::page_dot(const Eigen::Vector2d& lattice_mm) const {
    return pattern.raster_position(lattice_mm) + Eigen::Vector2d(offset_x, offset_y);
}

Eigen::Vector2d SheetLayout::page_mm(const Eigen::Vector2d& lattice_mm) const {
    const Eigen::Vector2d dot = page_dot(lattice_mm);
    return {(dot.x() + 0.5) * dot_x, (dot.y() + 0.5) * dot_y};
}

bool MarkerShape::in_cell(const Eigen::Vector2d& point) const {
    // Convex cell: the point lies on the same side of every edge.
    double sign = 0.0;
    for (std::size_t k = 0; k < cell.size(); ++k) {
        const Eigen::Vector2d edge = cell[(k + 1) % cell.size()] - cell[k], to = point - cell[k];
        const double side = edge.x() * to.y() - edge.y() * to.x();
        if (side * sign < 0.0) return false;
        if (side != 0.0) sign = side;
    }
    return true;
}

bool MarkerShape::inked(const Eigen::Vector2d& point) const {
    const Eigen::Vector2d d = point - centre;
    const double half = 0.5 * line_width;
    if (std::abs(d.norm() - radius) <= half) return true;
    return (std::abs(d.y()) <= half && std::abs(d.x()) <= arm) || (std::abs(d.x()) <= half && std::abs(d.y()) <= arm);
}

std::vector<MarkerShape> marker_shapes(const optics::Design& design, double dot_x, double dot_y) {
    std::vector<MarkerShape> shapes;
    const auto lattice = marker_lattice(design);
    if (!lattice) return shapes;
    // Ring and crosshair inside 0.9 of the cell's inscribed circle, so the ink is symmetric
    // about the lenslet's centre.
    const double inradius = lattice->kind() == optics::LatticeKind::Hexagonal
                                ? 0.5 * lattice->pitch_x()
                                : 0.5 * std::min(lattice->pitch_x(), lattice->pitch_y());
    const int nx = lattice->count_x(), ny = lattice->count_y();
    // Row ends of a hexagonal lattice: the outermost lenslet of the first and last rows.
    const optics::CellIndex corners[] = {{0, ny - 1}, {nx - 1, ny - 1}, {0, 0}, {nx - 1, 0}};
    for (const optics::CellIndex cell : corners) {
        MarkerShape m;
        m.lenslet = cell;
        m.centre = lattice->center(cell);
        for (const Eigen::Vector2d& corner : lattice->cell_corners()) m.cell.push_back(m.centre + corner);
        m.radius = 0.55 * inradius;
        m.arm = 0.9 * inradius;
        m.line_width = std::max(0.06 * inradius, 1.5 * std::max(dot_x, dot_y));
        shapes.push_back(std::move(m));
    }
    return shapes;
}

SheetLayout layout_sheet(const optics::Design& design, const PrinterProfile& printer,
                         const patterns::PatternGeometry& pattern, const SheetInfo& info) {
    RFD_CHECK(pattern.width > 0 && pattern.height > 0);
    SheetLayout l;
    l.paper = printer.paper;
    l.dpi_x = printer.dpi_x.value;
    l.dpi_y = printer.dpi_y.value;
    l.dot_x = printer.dpi_x.dot_mm();
    l.dot_y = printer.dpi_y.dot_mm();
    l.pattern = pattern;
    l.mirror = info.mirror;
    // Whole dots inside the paper; a hair of tolerance against 210 mm being 23811.0000001 dots.
    l.page_width = static_cast<int>(std::floor(l.paper.width / l.dot_x + 1e-9));
    l.page_height = static_cast<int>(std::floor(l.paper.height / l.dot_y + 1e-9));

    const Eigen::Vector2d size = pattern.size_mm();
    const double printable_w = l.paper.width - 2 * l.paper.margin;
    const double printable_h = l.paper.height - 2 * l.paper.margin;
    if (size.x() + 2 * kSideRoom > printable_w || size.y() + kTopRoom + kBottomRoom > printable_h) {
        char text[512];
        std::snprintf(text, sizeof text,
                      "the pattern (%.1f x %.1f mm) and its marks (%.0f mm at the sides, %.0f mm above "
                      "and below) do not fit the printable area of %s paper (%.1f x %.1f mm)",
                      size.x(), size.y(), kSideRoom, kTopRoom, l.paper.name.c_str(), printable_w,
                      printable_h);
        throw InputError(SourceLocation{printer.file, 0, 0, "paper"}, text);
    }
    // Copies in a grid of blocks (a pattern with its room for marks), whole dots apart.
    const int step_x = static_cast<int>(std::ceil((size.x() + 2 * kSideRoom) / l.dot_x - 1e-9));
    const int step_y = static_cast<int>(std::ceil((size.y() + kTopRoom + kBottomRoom) / l.dot_y - 1e-9));
    const int fit_x = 1 + static_cast<int>(std::floor((printable_w - size.x() - 2 * kSideRoom) / (step_x * l.dot_x)));
    const int fit_y = 1 + static_cast<int>(std::floor((printable_h - size.y() - kTopRoom - kBottomRoom) / (step_y * l.dot_y)));
    if (info.copies < 0) throw InputError(SourceLocation{"", 0, 0, "--copies"}, "expected 0 (as many as fit) or more");
    const int copies = info.copies == 0 ? fit_x * fit_y : info.copies;
    if (copies > fit_x * fit_y)
        throw InputError(SourceLocation{"", 0, 0, "--copies"},
                         std::to_string(copies) + " copies of the pattern do not fit on " + l.paper.name +
                             " paper: at most " + std::to_string(fit_x * fit_y) + " (" + std::to_string(fit_x) +
                             " x " + std::to_string(fit_y) + ")");
    const int columns = std::min(copies, fit_x), rows = (copies + columns - 1) / columns;
    l.copies.clear();
    for (int k = 0; k < copies; ++k) l.copies.emplace_back(k % columns * step_x, k / columns * step_y);
    l.offset_x = (l.page_width - (columns - 1) * step_x - pattern.width) / 2;
    l.offset_y = (l.page_height - (rows - 1) * step_y - pattern.height) / 2;

    for (const MarkerShape& shape : marker_shapes(design, l.dot_x, l.dot_y)) {
        Marker m;
        m.lenslet = shape.lenslet;
        m.centre = l.page_mm(shape.centre);
        for (const Eigen::Vector2d& corner : shape.cell) m.cell.push_back(l.page_mm(corner));
        m.radius = shape.radius;
        m.arm = shape.arm;
        m.line_width = shape.line_width;
        l.markers.push_back(std::move(m));
    }
    l.label = label_lines(design, printer, info);
    return l;
}

void trace_clear_regions(cairo_t* cr, const SheetLayout& layout) {
    for (std::size_t copy = 0; copy < layout.copies.size(); ++copy) {
        const Eigen::Vector2d shift = layout.copy_mm(copy);
        for (const Marker& m : layout.markers) {
            cairo_move_to(cr, m.cell.front().x() + shift.x(), m.cell.front().y() + shift.y());
            for (std::size_t k = 1; k < m.cell.size(); ++k)
                cairo_line_to(cr, m.cell[k].x() + shift.x(), m.cell[k].y() + shift.y());
            cairo_close_path(cr);
        }
    }
}

namespace {

// One copy's markers, crop marks and ruler (user units: page-frame mm, at the first copy).
void draw_copy_marks(cairo_t* cr, const SheetLayout& layout) {
    // Markers: a ring and a crosshair, all within 0.9 of the cell's inradius.
    for (const Marker& m : layout.markers) {
        const double arm = m.arm;
        cairo_set_line_width(cr, m.line_width);
        cairo_new_sub_path(cr);
        cairo_arc(cr, m.centre.x(), m.centre.y(), m.radius, 0.0, 2.0 * kPi);
        cairo_stroke(cr);
        cairo_move_to(cr, m.centre.x() - arm, m.centre.y());
        cairo_line_to(cr, m.centre.x() + arm, m.centre.y());
        cairo_move_to(cr, m.centre.x(), m.centre.y() - arm);
        cairo_line_to(cr, m.centre.x(), m.centre.y() + arm);
        cairo_stroke(cr);
    }
    // Crop marks: an L outside each corner of the pattern, on its boundary lines.
    const Eigen::Vector2d lo = layout.pattern_min(), hi = layout.pattern_max();
    cairo_set_line_width(cr, kMarkLine);
    for (const double x : {lo.x(), hi.x()})
        for (const double y : {lo.y(), hi.y()}) {
            const double sx = x == lo.x() ? -1.0 : 1.0, sy = y == lo.y() ? -1.0 : 1.0;
            cairo_move_to(cr, x + sx * kCropGap, y);
            cairo_line_to(cr, x + sx * (kCropGap + kCropLength), y);
            cairo_move_to(cr, x, y + sy * kCropGap);
            cairo_line_to(cr, x, y + sy * (kCropGap + kCropLength));
        }
    cairo_stroke(cr);
    // Ruler below the pattern, from its left edge: ticks every mm, longer every 5 and 10,
    // numbered every 10 mm; it checks the printer's scale with a steel rule.
    cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    const double base = hi.y() + 2.0;
    const int length = std::max(10, static_cast<int>(std::floor(hi.x() - lo.x())));
    cairo_set_line_width(cr, kRulerLine);
    cairo_move_to(cr, lo.x(), base);
    cairo_line_to(cr, lo.x() + length, base);
    for (int k = 0; k <= length; ++k) {
        const double tick = k % 10 == 0 ? 3.0 : k % 5 == 0 ? 2.0 : 1.2;
        cairo_move_to(cr, lo.x() + k, base);
        cairo_line_to(cr, lo.x() + k, base + tick);
    }
    cairo_stroke(cr);
    for (int k = 0; k <= length; k += 10)
        show_text_at(cr, std::to_string(k) + (k == 0 ? " mm" : ""), lo.x() + k + 0.3,
                     base + 3.0 + kRulerFont, kRulerFont);
}

}  // namespace

void draw_marks(cairo_t* cr, const SheetLayout& layout) {
    cairo_save(cr);
    cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
    for (std::size_t copy = 0; copy < layout.copies.size(); ++copy) {
        const Eigen::Vector2d shift = layout.copy_mm(copy);
        cairo_save(cr);
        cairo_translate(cr, shift.x(), shift.y());
        draw_copy_marks(cr, layout);
        cairo_restore(cr);
    }
    const Eigen::Vector2d lo = layout.pattern_min();
    cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    // Label above the pattern and its crop marks, centred on the paper, shrunk to the
    // printable width.
    double font = kLabelFont;
    cairo_set_font_size(cr, font);
    double widest = 0.0;
    for (const std::string& line : layout.label) {
        cairo_text_extents_t extents;
        cairo_text_extents(cr, line.c_str(), &extents);
        widest = std::max(widest, extents.width);
    }
    const double printable = layout.paper.width - 2 * layout.paper.margin;
    if (widest > printable) font *= printable / widest;
    const double centre = 0.5 * layout.paper.width;
    for (std::size_t k = 0; k < layout.label.size(); ++k) {
        const double y = lo.y() - kCropGap - kCropLength - 1.5 -
                         static_cast<double>(layout.label.size() - 1 - k) * 1.4 * font;
        show_text_at(cr, layout.label[k], 0.0, y, font, centre);
    }
    cairo_restore(cr);
}

}  // namespace rfd::print
