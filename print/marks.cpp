#include "print/marks.hpp"

#include <cmath>
#include <numbers>

namespace rfd::print {

SheetMarks sheet_marks(const Paper& paper) {
    SheetMarks marks;
    const double inset = 0.5 * marks.corner_diameter + 1.0;  // centre from the printable edge
    const double left = paper.margin + inset, right = paper.width - paper.margin - inset;
    const double top = paper.margin + inset, bottom = paper.height - paper.margin - inset;
    marks.corners = {Eigen::Vector2d(left, top), Eigen::Vector2d(right, top), Eigen::Vector2d(right, bottom),
                     Eigen::Vector2d(left, bottom)};
    marks.orientation = Eigen::Vector2d(left, top + 1.5 * marks.corner_diameter);
    return marks;
}

void draw_marks(cairo_t* cr, const SheetMarks& marks) {
    cairo_save(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    const auto disc = [&](const Eigen::Vector2d& centre, double diameter) {
        cairo_new_sub_path(cr);
        cairo_arc(cr, centre.x(), centre.y(), 0.5 * diameter, 0.0, 2.0 * std::numbers::pi);
        cairo_close_path(cr);
    };
    for (const Eigen::Vector2d& corner : marks.corners) disc(corner, marks.corner_diameter);
    disc(marks.orientation, marks.orientation_diameter);
    cairo_fill(cr);
    cairo_restore(cr);
}

}  // namespace rfd::print
