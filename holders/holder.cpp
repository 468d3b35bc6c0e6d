#include "holders/holder.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "core/error.hpp"

namespace rfd::holders {
namespace {

constexpr double kPi = std::numbers::pi;

// Area of a regular n-gon circumscribed about a circle of radius r: n r^2 tan(pi/n).
double circumscribed_polygon_area(double r, int n) {
    return n * r * r * std::tan(kPi / n);
}

double lerp(double a, double b, double t) { return a + t * (b - a); }

}  // namespace

namespace {

struct Box2 {
    double x0, x1, y0, y1;
};

// The axis-aligned rectangles a Rect or Cells section cuts at z.
void rect_pieces(const Section& s, double z, std::vector<Box2>& out) {
    if (z < s.z0.value || z > s.z1.value) return;
    const double span = s.z1.value - s.z0.value;
    const double t = span > 0 ? (z - s.z0.value) / span : 0.0;
    if (s.kind == Section::Kind::Rect) {
        const double w = lerp(s.width.value, s.width1.value, t), h = lerp(s.height.value, s.height1.value, t);
        if (w > 0 && h > 0) out.push_back({-w / 2, w / 2, -h / 2, h / 2});
        if (s.notches) {
            const double half = s.notches->size.value / 2;
            for (const double sx : {-1.0, 1.0})
                for (const double sy : {-1.0, 1.0}) {
                    const double x = sx * s.notches->x.value, y = sy * s.notches->y.value;
                    out.push_back({x - half, x + half, y - half, y + half});
                }
        }
    } else if (s.kind == Section::Kind::Cells) {
        const double cw = s.clip ? (*s.clip)[0].value / 2 : 1e300, ch = s.clip ? (*s.clip)[1].value / 2 : 1e300;
        for (int j = 0; j < s.cells.count_y(); ++j)
            for (int i = 0; i < s.cells.count_x(); ++i) {
                const Eigen::Vector2d c = s.cells.center({i, j});
                const Box2 b{std::max(c.x() - s.width.value / 2, -cw), std::min(c.x() + s.width.value / 2, cw),
                             std::max(c.y() - s.height.value / 2, -ch), std::min(c.y() + s.height.value / 2, ch)};
                if (b.x1 > b.x0 && b.y1 > b.y0) out.push_back(b);
            }
    }
}

// Area of a union of rectangles, on the grid of their edges.
double union_area(const std::vector<Box2>& boxes) {
    std::vector<double> xs, ys;
    for (const Box2& b : boxes) {
        xs.push_back(b.x0), xs.push_back(b.x1);
        ys.push_back(b.y0), ys.push_back(b.y1);
    }
    std::sort(xs.begin(), xs.end());
    std::sort(ys.begin(), ys.end());
    xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
    ys.erase(std::unique(ys.begin(), ys.end()), ys.end());
    double area = 0.0;
    for (std::size_t i = 0; i + 1 < xs.size(); ++i)
        for (std::size_t j = 0; j + 1 < ys.size(); ++j) {
            const double cx = (xs[i] + xs[i + 1]) / 2, cy = (ys[j] + ys[j + 1]) / 2;
            for (const Box2& b : boxes)
                if (b.x0 <= cx && cx <= b.x1 && b.y0 <= cy && cy <= b.y1) {
                    area += (xs[i + 1] - xs[i]) * (ys[j + 1] - ys[j]);
                    break;
                }
        }
    return area;
}

}  // namespace

double Section::area_at(double z) const {
    if (z < z0.value || z > z1.value) return 0.0;
    const double span = z1.value - z0.value;
    const double t = span > 0 ? (z - z0.value) / span : 0.0;
    switch (kind) {
    case Kind::Rect:
    case Kind::Cells: {
        std::vector<Box2> boxes;
        rect_pieces(*this, z, boxes);
        return union_area(boxes);
    }
    case Kind::Circle:
        return circumscribed_polygon_area(lerp(width.value, width1.value, t) / 2, facets);
    case Kind::Revolved: {
        // Where the profile's edges cross this z, inside-outside in pairs along r.
        std::vector<double> radii;
        for (std::size_t k = 0; k < profile.size(); ++k) {
            const auto& a = profile[k];
            const auto& b = profile[(k + 1) % profile.size()];
            const double za = a[1].value, zb = b[1].value;
            if ((za <= z && z < zb) || (zb <= z && z < za))
                radii.push_back(lerp(a[0].value, b[0].value, (z - za) / (zb - za)));
        }
        std::sort(radii.begin(), radii.end());
        double sum = 0.0;
        for (std::size_t k = 0; k + 1 < radii.size(); k += 2)
            sum += circumscribed_polygon_area(radii[k + 1], facets) - circumscribed_polygon_area(radii[k], facets);
        return sum;
    }
    }
    return 0.0;
}

double Section::half_height_max() const {
    switch (kind) {
    case Kind::Rect: {
        double h = std::max(height.value, height1.value) / 2;
        if (notches) h = std::max(h, notches->y.value + notches->size.value / 2);
        return h;
    }
    case Kind::Circle:
        return std::max(width.value, width1.value) / 2 / std::cos(kPi / facets);
    case Kind::Cells: {
        double h = 0.0;
        for (int j = 0; j < cells.count_y(); ++j)
            h = std::max(h, std::abs(cells.center({0, j}).y()) + height.value / 2);
        return clip ? std::min(h, (*clip)[1].value / 2) : h;
    }
    case Kind::Revolved: {
        double r = 0.0;
        for (const auto& p : profile) r = std::max(r, p[0].value);
        return r / std::cos(kPi / facets);
    }
    }
    return 0.0;
}

bool ClearAperture::contains(const Eigen::Vector2d& p) const {
    const auto in_window = [&](const Eigen::Vector2d& q) {
        return std::abs(q.x()) <= half_width && std::abs(q.y()) <= half_height;
    };
    const auto in_notch = [&](const Eigen::Vector2d& q) {
        return notch && std::abs(std::abs(q.x()) - (*notch)[0]) <= (*notch)[2] &&
               std::abs(std::abs(q.y()) - (*notch)[1]) <= (*notch)[2];
    };
    switch (kind) {
    case Kind::Circle: return p.norm() <= radius;
    case Kind::Window: return in_window(p);
    case Kind::WholeCells: {
        const optics::CellIndex cell = lattice.cell_at(p);
        if (!lattice.contains(cell)) return false;
        // The cell's bounding box: flats at +-pitch/2, corners (hexagonal) at +-pitch/sqrt(3).
        const Eigen::Vector2d c = lattice.center(cell);
        const double hx = lattice.pitch_x() / 2;
        const double hy = lattice.kind() == optics::LatticeKind::Hexagonal ? lattice.pitch_x() / std::sqrt(3.0)
                                                                           : lattice.pitch_y() / 2;
        for (const Eigen::Vector2d& corner : {Eigen::Vector2d(c.x() - hx, c.y() - hy), Eigen::Vector2d(c.x() + hx, c.y() - hy),
                                             Eigen::Vector2d(c.x() - hx, c.y() + hy), Eigen::Vector2d(c.x() + hx, c.y() + hy)})
            if (!in_window(corner) && !in_notch(corner)) return false;
        return true;
    }
    case Kind::InsetCells: {
        if (!in_window(p)) return false;
        const optics::CellIndex cell = lattice.cell_at(p);
        if (!lattice.contains(cell)) return false;
        const Eigen::Vector2d local = p - lattice.center(cell);
        return std::abs(local.x()) <= lattice.pitch_x() / 2 - inset &&
               std::abs(local.y()) <= lattice.pitch_y() / 2 - inset;
    }
    }
    return false;
}

double Holder::cavity_area_at(double z) const {
    // Rectangular cuts may overlap one another (Design I's corner sights cross the window
    // and the pocket): their union counts once. Round cuts meet the others only end to end.
    std::vector<Box2> boxes;
    double area = 0.0;
    for (const Section& s : sections) {
        if (s.kind == Section::Kind::Rect || s.kind == Section::Kind::Cells)
            rect_pieces(s, z, boxes);
        else
            area += s.area_at(z);
    }
    return area + union_area(boxes);
}

double Holder::cavity_volume() const {
    // Every section's area is a polynomial of degree <= 2 in z between these breakpoints,
    // so Simpson's rule on each interval is exact (up to rounding).
    std::vector<double> breaks;
    for (const Section& s : sections) {
        breaks.push_back(s.z0.value);
        breaks.push_back(s.z1.value);
        for (const auto& p : s.profile) breaks.push_back(p[1].value);
    }
    std::sort(breaks.begin(), breaks.end());
    breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());
    double volume = 0.0;
    for (std::size_t k = 0; k + 1 < breaks.size(); ++k) {
        // Sample just inside the interval: a section's area jumps at its own ends.
        const double a = breaks[k], b = breaks[k + 1], h = b - a;
        if (h <= 0) continue;
        const double inset = h * 1e-9;
        volume += h / 6 * (cavity_area_at(a + inset) + 4 * cavity_area_at((a + b) / 2) + cavity_area_at(b - inset));
    }
    return volume;
}

double Holder::part_volume(const PrintedPart& part) const {
    const double y0 = part.y0.value, y1 = part.y1.value;
    double volume = width.value * (y1 - y0) * (z_back.value - z_front.value);
    double reach = 0.0;
    for (const Section& s : sections) reach = std::max(reach, s.half_height_max());
    const double cavity = cavity_volume();
    constexpr double tiny = 1e-9;
    for (const Eigen::Vector2d& c : cells) {
        const bool below_in = c.y() - reach >= y0 - tiny && c.y() <= y1 + tiny;
        const bool above_in = c.y() >= y0 - tiny && c.y() + reach <= y1 + tiny;
        const bool below_out = c.y() <= y0 + tiny || c.y() - reach >= y1 - tiny;
        const bool above_out = c.y() + reach <= y0 + tiny || c.y() >= y1 - tiny;
        // Parts are cut through cell centres only: each half of a cell's cavity lies wholly
        // inside or wholly outside a part.
        RFD_CHECK((below_in || below_out) && (above_in || above_out));
        volume -= cavity * (0.5 * below_in + 0.5 * above_in);
    }
    return volume;
}

std::array<Eigen::Vector3d, 2> Holder::part_box(const PrintedPart& part) const {
    return {Eigen::Vector3d(-width.value / 2, part.y0.value, z_front.value),
            Eigen::Vector3d(width.value / 2, part.y1.value, z_back.value)};
}

const PrintedPart& Holder::part(const std::string& name) const {
    for (const PrintedPart& p : parts)
        if (p.name == name) return p;
    RFD_CHECK(false && "no such printed part");
    return parts.front();
}

namespace {

std::string extrude(const Section& s, const std::string& shape, const std::string& scale) {
    const Expr eps("eps", 0.0);
    const Expr z0 = s.overlap_front ? s.z0 - eps : s.z0, z1 = s.overlap_back ? s.z1 + eps : s.z1;
    return "    translate([0, 0, " + z0.text + "])\n        linear_extrude(height = " + (z1 - z0).text + scale +
           ")\n            " + shape + ";\n";
}

std::string section_body(const Section& s) {
    switch (s.kind) {
    case Section::Kind::Rect: {
        std::string shape = "square([" + s.width.text + ", " + s.height.text + "], center = true)";
        if (s.notches)
            shape = "union() {\n                " + shape + ";\n                for (sx = [-1, 1], sy = [-1, 1])\n"
                    "                    translate([sx * " + s.notches->x.text + ", sy * " + s.notches->y.text +
                    "]) square(" + s.notches->size.text + ", center = true);\n            }";
        const bool frustum = s.width1.text != s.width.text || s.height1.text != s.height.text;
        const std::string scale =
            frustum ? ", scale = [" + (s.width1 / s.width).text + ", " + (s.height1 / s.height).text + "]" : "";
        return extrude(s, shape, scale);
    }
    case Section::Kind::Circle: {
        const std::string n = std::to_string(s.facets);
        const Expr circumscribed = s.width / cos_deg(Expr("180 / " + n, 180.0 / s.facets, Expr::Product));
        const std::string shape = "circle(d = " + circumscribed.text + ", $fn = " + n + ")";
        const bool frustum = s.width1.text != s.width.text;
        return extrude(s, shape, frustum ? ", scale = " + (s.width1 / s.width).text : "");
    }
    case Section::Kind::Cells: {
        RFD_CHECK(s.cells.kind() == optics::LatticeKind::Rectangular);
        const std::string& p = s.cells_prefix;
        std::string shape = "for (i = [0 : " + p + "_count_x - 1], j = [0 : " + p + "_count_y - 1])\n"
                            "                translate([(i - (" + p + "_count_x - 1) / 2) * " + p + "_pitch_x, (j - (" + p +
                            "_count_y - 1) / 2) * " + p + "_pitch_y])\n                    square([" + s.width.text +
                            ", " + s.height.text + "], center = true)";
        if (s.clip)
            shape = "intersection() {\n            " + shape + ";\n            square([" + (*s.clip)[0].text + ", " +
                    (*s.clip)[1].text + "], center = true);\n        }";
        return extrude(s, shape, "");
    }
    case Section::Kind::Revolved: {
        const std::string n = std::to_string(s.facets);
        std::string points;
        for (const auto& p : s.profile)
            points += (points.empty() ? "" : ",\n                 ") + std::string("[") + p[0].text + ", " + p[1].text + "]";
        return "    // A circle of " + n + " facets drawn through the profile's radii would be smaller than\n"
               "    // the bore it stands for; scaling by 1 / cos(180 / " + n + ") circumscribes it.\n"
               "    scale([1 / cos(180 / " + n + "), 1 / cos(180 / " + n + "), 1])\n        rotate_extrude($fn = " + n +
               ")\n            polygon([" + points + "]);\n";
    }
    }
    return "";
}

}  // namespace

std::string to_scad(const Holder& h) {
    std::ostringstream out;
    out << "// " << h.title << "\n// Generated by rfd holder from \"" << h.design_name << "\" (Design " << h.design_kind
        << ").\n//\n// Frame: z along the optical axis in the direction light travels (plane A's vertex at\n"
           "// z = 0), y up as the observer sees the display; millimetres. Build one printed part with\n"
           "//   openscad -D 'part=\"" << h.parts.front().name << "\"' -o " << h.parts.front().name << ".stl holder.scad\n//\n";
    for (const std::string& note : h.notes) out << "// " << note << "\n";
    out << "\npart = \"assembly\";  // ";
    for (std::size_t k = 0; k < h.parts.size(); ++k) out << h.parts[k].name << " | ";
    out << "assembly\n\n" << h.parameters.text() << "\n";

    for (const Section& s : h.sections) {
        out << "// " << s.comment << "\nmodule " << s.module << "() {\n" << section_body(s) << "}\n\n";
    }
    out << "module cell_cavity() {\n";
    for (const Section& s : h.sections) out << "    " << s.module << "();\n";
    out << "}\n\n";
    // Each part is cut from its own slab of the block, and only the cells that reach into
    // that slab are subtracted: OpenSCAD's CGAL subtracts faster the fewer cuts it meets.
    // The outer parts' slabs are the box's own faces; the cuts reach past them by eps.
    double reach = 0.0;
    for (const Section& s : h.sections) reach = std::max(reach, s.half_height_max());
    for (const PrintedPart& p : h.parts) {
        out << "// " << p.print_note << "\nmodule part_" << p.name << "() {\n    difference() {\n        translate(["
            << (-(h.width / 2)).text << ", " << p.y0.text << ", " << h.z_front.text << "])\n            cube(["
            << h.width.text << ", " << (p.y1 - p.y0).text << ", " << (h.z_back - h.z_front).text << "]);\n";
        for (std::size_t k = 0; k < h.cells.size(); ++k) {
            const Eigen::Vector2d& c = h.cells[k];
            if (c.y() + reach <= p.y0.value + 1e-9 || c.y() - reach >= p.y1.value - 1e-9) continue;
            if (!h.cell_grid) {
                out << "        cell_cavity();\n";
                continue;
            }
            const auto& g = *h.cell_grid;
            const int i = static_cast<int>(k % static_cast<std::size_t>(g[0].value + 0.5));
            const int j = static_cast<int>(k / static_cast<std::size_t>(g[0].value + 0.5));
            const Expr x = (Expr(i) - (g[0] - 1) / 2) * g[2], y = (Expr(j) - (g[1] - 1) / 2) * g[3];
            out << "        translate([" << x.text << ", " << y.text << ", 0]) cell_cavity();\n";
        }
        out << "    }\n}\n\n";
    }
    out << "if (part == \"assembly\") {\n";
    for (const PrintedPart& p : h.parts) {
        if (p.copies > 1 && h.cell_grid)
            out << "    for (k = [0 : " << p.copies - 1 << "]) translate([0, k * " << (*h.cell_grid)[3].text
                << ", 0]) part_" << p.name << "();\n";
        else
            out << "    part_" << p.name << "();\n";
    }
    out << "}\n";
    for (const PrintedPart& p : h.parts) out << "else if (part == \"" << p.name << "\") part_" << p.name << "();\n";
    out << "else assert(false, str(\"part must be one of the printed parts or assembly, not \", part));\n";
    return out.str();
}

}  // namespace rfd::holders
