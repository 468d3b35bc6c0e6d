#pragma once
// A lens holder as data: a printed block with a cavity cut through it along the optical
// axis, split into parts that print without supports, plus what the checks need to know
// (where every part must sit, where the light must pass). holders/generate.hpp makes one
// from a design; to_scad() writes it as parametric OpenSCAD.
//
// Frame: the design's (optics/design.hpp): z along the optical axis in the direction the
// light travels, origin at plane A's vertex, x to the right and y up as the observer sees
// the display, millimetres. The holder is the box |x| <= width/2, |y| <= height/2,
// z_front <= z <= z_back, minus the cavity. The cavity of one cell is a row of sections
// along z (pockets that hold parts, channels that let the light through); Design IV
// repeats the cell at every macro-pixel centre. Every section is symmetric about x = 0
// and y = 0 of its cell, so the holder splits along y = const planes through cell centres
// into parts whose volumes are known in closed form.
//
// Each pocket is open at the split plane: a part is laid into the lower half and the upper
// half closes over it (thesis figures 8.9 and 8.12: "top half of housing removed").

#include <array>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "holders/expr.hpp"
#include "optics/lattice.hpp"

namespace rfd::holders {

/// Axis-aligned squares cut at (+-x, +-y) in every quadrant of a rectangle (Design I's
/// corner sight windows over the registration lenslets).
struct CornerNotches {
    Expr x, y;      ///< centre of the notch in the +x, +y quadrant
    Expr size;      ///< side of the square
};

/// One z-range of the cavity with its cross-section (which may grow linearly with z).
struct Section {
    enum class Kind {
        Rect,      ///< centred rectangle width x height at z0 growing to width1 x height1 at z1
        Circle,    ///< centred circle of diameter `width` growing to `width1`, `facets` sides
        Cells,     ///< a width x height hole at every lenslet centre, clipped by `clip`
        Revolved,  ///< `profile` (r, z) turned about the axis, `facets` sides
    };
    Kind kind = Kind::Rect;
    std::string module;    ///< OpenSCAD module name
    std::string comment;
    Expr z0, z1;
    Expr width, height;    ///< at z0
    Expr width1, height1;  ///< at z1 (Rect, Circle); equal to width, height for a prism
    int facets = 0;
    std::optional<CornerNotches> notches;   ///< Rect prisms only
    optics::Lattice cells = optics::Lattice::rectangular(1, 1, 1, 1);  ///< Cells
    std::string cells_prefix;               ///< parameters cells_prefix_count_x, ... (Cells)
    std::optional<std::array<Expr, 2>> clip;  ///< Cells: clipping rectangle (w, h)
    std::vector<std::array<Expr, 2>> profile; ///< Revolved: (r, z) points, counter-clockwise
    /// Reach eps past z0 (z1) into the neighbouring cut, so that no faces coincide. A
    /// pocket never does: its faces are seats. A channel does where its neighbour is wider.
    bool overlap_front = false, overlap_back = false;

    /// Area of the cross-section at z (0 outside [z0, z1]); exact for the polygon OpenSCAD
    /// builds (circles as circumscribed polygons of `facets` sides, so a bore is never
    /// smaller than its nominal diameter).
    double area_at(double z) const;
    /// Largest |y| the section reaches (for splitting checks).
    double half_height_max() const;
};

/// One printed part: the holder between two y planes.
struct PrintedPart {
    std::string name;        ///< "base", "lid", "bottom", "middle", "top"
    Expr y0, y1;
    int copies = 1;          ///< identical parts to print (Design IV's middle plates)
    std::string print_note;  ///< how it lies on the printer's bed
};

/// A face the holder offers a part to rest against, and where the design wants it.
struct Seat {
    std::string plane;          ///< "A", "B", ...
    std::string what;           ///< which face of the part rests on it
    double z = 0.0;             ///< where the seat face must be, mm
    Eigen::Vector2d probe;      ///< a point of the seat face (x, y) in the holder frame
    double probe_from_z = 0.0;  ///< a z inside the pocket, in front of (or behind) the face
};

/// The part of a plane that the holder leaves clear for light.
struct ClearAperture {
    enum class Kind {
        Circle,      ///< |p| <= radius
        Window,      ///< |x| <= half_width, |y| <= half_height
        WholeCells,  ///< the point's lenslet lies wholly inside the window or a notch
        InsetCells,  ///< the point lies inside its lenslet cell shrunk by `inset`, and in the window
    };
    std::string plane;
    Kind kind = Kind::Window;
    double radius = 0.0;
    double half_width = 0.0, half_height = 0.0;
    std::optional<std::array<double, 3>> notch;  ///< (x, y, half side) of the +x+y notch
    optics::Lattice lattice = optics::Lattice::rectangular(1, 1, 1, 1);
    double inset = 0.0;

    bool contains(const Eigen::Vector2d& p) const;
};

struct Holder {
    std::string design_name;
    std::string design_kind;
    std::string title;                 ///< one line: what this holder is
    std::vector<std::string> notes;    ///< assembly notes, for the .scad header and the report
    ScadParameters parameters;
    Expr width, height, z_front, z_back;     ///< the outer box
    std::vector<Section> sections;           ///< the cavity of one cell, front to back
    std::vector<Eigen::Vector2d> cells;      ///< cell centres (x, y); {(0, 0)} unless Design IV
    std::optional<std::array<Expr, 4>> cell_grid;  ///< Design IV: count_x, count_y, pitch_x, pitch_y
    std::vector<PrintedPart> parts;
    std::vector<Seat> seats;
    std::vector<ClearAperture> apertures;
    double fov_half_deg = 0.0;               ///< incident half-angle the holder was sized for

    /// Cross-section area of one cell's cavity at z.
    double cavity_area_at(double z) const;
    /// Volume of one cell's cavity (Simpson's rule between section ends: exact for the
    /// prisms and frustums the holder is made of).
    double cavity_volume() const;
    /// Volume of a printed part, closed form.
    double part_volume(const PrintedPart& part) const;
    /// Bounding box of a printed part: min and max corners.
    std::array<Eigen::Vector3d, 2> part_box(const PrintedPart& part) const;
    const PrintedPart& part(const std::string& name) const;
};

/// The holder as an OpenSCAD program: parameters first, one module per section and per
/// printed part, and `part = "..."` at the top choosing what to build (openscad -D).
std::string to_scad(const Holder& holder);

}  // namespace rfd::holders
