#pragma once
// Registration marks of the calibration sheets (`rfd print wedge`, `rfd print moire`): a black
// disc in each corner of the printable area and a smaller one below the top-left disc, so that
// a photograph of the sheet, taken from any side or scanned from the back of the film, is
// mapped to the page without ambiguity (calibrate/sheet_finder.hpp). Page frame as layout.hpp:
// mm, y down.
//
// Example: const SheetMarks marks = sheet_marks(printer.paper); draw_marks(cr, marks);

#include <array>

#include <Eigen/Core>

#include "print/printer.hpp"

// Cairo's context, declared as cairo.h does (Cairo stays private to rfd_print).
typedef struct _cairo cairo_t;

namespace rfd::print {

struct SheetMarks {
    /// Centres of the corner discs: top left, top right, bottom right, bottom left.
    std::array<Eigen::Vector2d, 4> corners;
    Eigen::Vector2d orientation;        ///< centre of the small disc below the top-left one
    double corner_diameter = 6.0;       ///< mm
    double orientation_diameter = 3.0;  ///< mm
    /// Room the marks take from the printable area's top and bottom edges, mm: sheets keep
    /// their content out of these strips except where they indent past the discs.
    double strip = 9.0;
    /// Indent of text that starts in the top strip, from the printable area's left edge, mm.
    double indent = 10.0;
};

/// The marks of a sheet on `paper`.
SheetMarks sheet_marks(const Paper& paper);

/// Draws the discs in black (user units: page-frame mm).
void draw_marks(cairo_t* cr, const SheetMarks& marks);

}  // namespace rfd::print
