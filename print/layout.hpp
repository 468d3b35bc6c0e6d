#pragma once
// Where everything lies on a printed sheet (thesis 8.4.1): the pattern at the printer's
// true resolution, centred on the paper; registration markers under the four drilled
// corner lenslets; crop marks at the pattern's boundary; a millimetre ruler below it; a
// label above it.
//
// Page frame: millimetres from the paper's top-left corner, x to the right, y down, as the
// sheet lies in the printer (front side). Page dots: dot (X, Y) covers
// [X dot_x, (X + 1) dot_x] x [Y dot_y, (Y + 1) dot_y]; continuous dot coordinates put dot
// centres at integers. Pattern dot (px, py) is page dot (px + offset_x, py + offset_y), so
// the pattern's dots fall exactly on the printer's dots.
//
// Markers: Designs I and II put them on the corner cells of the lenslet array
// (optics::DesignOptics::lattice(), whose frame is the pattern raster's lattice frame),
// Design III on the corner cells of the pattern plane's array. The whole corner cell is
// printed clear and carries a crosshair and a ring centred on the lenslet's centre, all
// inside the cell's inscribed circle so the ink is symmetric about that centre. Design IV
// has no markers (the thesis cut and aligned its 6 x 5 arrays by hand); its crop marks
// bound the macro-pixel grid.
//
// Example: SheetLayout l = layout_sheet(design, printer, info, {"bottle.tif", 1.0, 2, false});

#include <string>
#include <vector>

#include <Eigen/Core>

#include "optics/design.hpp"
#include "patterns/raster.hpp"
#include "print/printer.hpp"

typedef struct _cairo cairo_t;

namespace rfd::print {

/// A registration marker in the pattern's lattice frame (mm, y up, as optics::Transparency
/// samples it): a corner lenslet's cell printed clear, and the ink of a ring and a crosshair
/// centred on the lenslet.
struct MarkerShape {
    optics::CellIndex lenslet;
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    std::vector<Eigen::Vector2d> cell;    ///< corners of the lenslet's cell, in order
    double radius = 0.0;                  ///< the ring's
    double arm = 0.0;                     ///< the crosshair's half-length
    double line_width = 0.0;

    bool in_cell(const Eigen::Vector2d& point) const;
    /// Whether `point` lies on the ring or the crosshair.
    bool inked(const Eigen::Vector2d& point) const;
};

/// The markers of `design` printed with dots of dot_x x dot_y mm (lines at least 1.5 dots
/// wide): on the corner cells of the array that layout.hpp's header names; none for Design IV.
std::vector<MarkerShape> marker_shapes(const optics::Design& design, double dot_x, double dot_y);

/// A registration marker on the page: the centre of a corner lenslet and the clear cell around it.
struct Marker {
    Eigen::Vector2d centre;               ///< page frame, mm
    std::vector<Eigen::Vector2d> cell;    ///< corners of the lenslet's cell, page frame, mm
    double radius = 0.0;                  ///< the marker's ring radius, mm
    double arm = 0.0;                     ///< the crosshair's half-length, mm
    double line_width = 0.0;              ///< mm
    optics::CellIndex lenslet;            ///< which corner lenslet
};

/// What the label says and how the sheet is printed.
struct SheetInfo {
    std::string pattern_name;   ///< file name of the pattern, for the label
    double brightness = 1.0;
    int sheets = 1;             ///< 1, or 2 (front + mirrored back)
    bool mirror = false;        ///< this is the mirrored back sheet
    int copies = 1;             ///< copies of the pattern on the page; 0: as many as fit
};

struct SheetLayout {
    Paper paper;
    double dot_x = 0.0, dot_y = 0.0;   ///< mm per printer dot
    double dpi_x = 0.0, dpi_y = 0.0;
    int page_width = 0, page_height = 0;  ///< whole printer dots inside the paper
    patterns::PatternGeometry pattern;    ///< the pattern raster at the printer's dpi
    int offset_x = 0, offset_y = 0;       ///< page dot of pattern dot (0, 0)
    std::vector<Marker> markers;
    std::vector<std::string> label;       ///< label lines, top to bottom
    bool mirror = false;
    /// Every copy of the pattern (with its markers, crop marks and ruler): page-dot shifts
    /// from the first, which `offset_x`, `offset_y` and `markers` describe; {0, 0} first,
    /// row by row. Copies of one row share their rows of page dots; rows do not overlap.
    std::vector<Eigen::Vector2i> copies{Eigen::Vector2i::Zero()};
    /// The shift of copy k in page-frame mm.
    Eigen::Vector2d copy_mm(std::size_t k) const { return {copies[k].x() * dot_x, copies[k].y() * dot_y}; }

    /// Continuous page dot coordinates of a point of the pattern's lattice frame.
    Eigen::Vector2d page_dot(const Eigen::Vector2d& lattice_mm) const;
    /// Page-frame millimetres of a point of the pattern's lattice frame.
    Eigen::Vector2d page_mm(const Eigen::Vector2d& lattice_mm) const;
    /// The pattern's rectangle on the page: top-left and bottom-right corners, mm.
    Eigen::Vector2d pattern_min() const { return {offset_x * dot_x, offset_y * dot_y}; }
    Eigen::Vector2d pattern_max() const {
        return {(offset_x + pattern.width) * dot_x, (offset_y + pattern.height) * dot_y};
    }
};

/// The longer side of a page's screen picture (write_page_png, --preview), pixels.
inline constexpr int kPagePreviewPixels = 800;

/// Room the marks need around the pattern, mm: crop marks at the sides, the label above,
/// the ruler below.
inline constexpr double kSideRoom = 6.0;
inline constexpr double kTopRoom = 15.0;
inline constexpr double kBottomRoom = 11.0;

/// Lays out a sheet for a pattern whose raster is `pattern` (the design's raster at the
/// printer's dpi): info.copies of it (0: as many as fit) in rows, the whole grid centred,
/// the label once above the first row. Throws InputError when the pattern and its marks do
/// not fit inside the paper's printable area (saying both sizes), or the copies asked for
/// do not (saying how many do).
SheetLayout layout_sheet(const optics::Design& design, const PrinterProfile& printer,
                         const patterns::PatternGeometry& pattern, const SheetInfo& info);

/// Adds to the current path of `cr` (user units: page-frame mm) the regions printed clear:
/// the cells of the registration markers, of every copy.
void trace_clear_regions(cairo_t* cr, const SheetLayout& layout);
/// Draws, with the current source of `cr`, all ink of the marks: every copy's markers, crop
/// marks and ruler, and the label (vector paths and text; user units: page-frame mm).
void draw_marks(cairo_t* cr, const SheetLayout& layout);

}  // namespace rfd::print
