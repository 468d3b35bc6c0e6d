#include "holders/generate.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "holders/beam.hpp"

namespace rfd::holders {
namespace {

using optics::Arrangement;
using optics::CurvedSide;
using optics::DesignKind;

const optics::PlanoConvex* lens_of(const optics::Part& part) {
    if (const auto* l = std::get_if<optics::LensPart>(&part)) return &l->lens;
    if (const auto* a = std::get_if<optics::LensletArrayPart>(&part)) return &a->lens;
    return nullptr;
}

// Depth of a plano-convex lens's curved face at radius r from its vertex.
double sag_at(const optics::PlanoConvex& lens, double r) {
    const double c = 1.0 / lens.radius;
    const double q = 1 - (1 + lens.conic) * c * c * r * r;
    return q > 0 ? c * r * r / (1 + std::sqrt(q)) : lens.center_thickness;
}

std::string format_mm(double v) { return scad_number(std::round(v * 1000) / 1000); }

// One pocket: a part, or parts that touch and are held together.
struct Slot {
    std::vector<const optics::Plane*> planes;
    std::string name;         // "A", "BC"
    std::string label;        // for comments: "main lens", "pattern sheets, spacer and diffuser"
    bool round = false;
    bool sheets = false;      // a stack of sheets, sized from the light
    Expr width, height;       // of the part (round: width is the diameter)
    Expr z0, z1;              // the pocket
    double seat_z = 0.0;
    bool seat_at_front = false;
    std::string seat_what;
    // Half-size of the light's way through the part at its faces: the clear aperture (for a
    // lens, also the dome that reaches out of the pocket into the channel).
    Eigen::Vector2d clear = Eigen::Vector2d::Zero();
    const optics::LensletArrayPart* array = nullptr;
};

struct Builder {
    const optics::Design& design;
    const HolderProfile& profile;
    const PatternFilm& pattern_film;
    Holder holder;
    Expr clearance, wall, seat, eps, margin, film, sheets;
    std::vector<Slot> slots;

    [[noreturn]] void fail(const optics::Plane& plane, const std::string& what) const {
        throw InputError(SourceLocation{plane.where.file, plane.where.line, 0, "planes." + plane.name},
                         "cannot hold this design: " + what);
    }

    Expr define(const std::string& name, const Expr& e, const std::string& comment = "") {
        return holder.parameters.define(name, e, comment);
    }

    void globals() {
        ScadParameters& p = holder.parameters;
        p.group("Printer (" + profile.name + ")");
        clearance = define("clearance", profile.clearance, "radial play of a slip fit; also the axial play of a pocket");
        wall = define("wall", profile.min_wall, "outer walls");
        seat = define("seat", profile.seat, "how far a seat reaches under a part's rim");
        margin = define("beam_margin", profile.beam_margin, "air between the light and the holder");
        eps = define("eps", 0.01, "overlap of touching cuts, so that no faces coincide");
        const int s = pattern_film.sheets;
        film = define("film", pattern_film.thickness, "one printed transparency (the film printer's profile)");
        sheets = define("pattern_sheets", s, s == 2 ? "front sheet and mirrored back sheet" : "transparencies per pattern");
    }

    // Parameters of one plane's part, and its pocket.
    Slot slot_for(const optics::Plane& plane) {
        Slot slot;
        slot.planes = {&plane};
        slot.name = plane.name;
        const std::string& n = plane.name;
        holder.parameters.group("Plane " + n + ": " + plane.role);
        const Expr z = define(n + "_z", plane.z, plane.part_name);
        const optics::PlanoConvex* lens = lens_of(*plane.part);
        if (const auto* sheet = std::get_if<optics::SheetPart>(&*plane.part)) {
            slot.sheets = true;
            slot.label = plane.part_name;
            const Expr t = define(n + "_thickness", sheet->thickness);
            slot.z0 = z;
            slot.z1 = z + t;
            return slot;
        }
        const Expr thickness = define(n + "_thickness", lens->center_thickness, "centre thickness");
        double band_radius = 0.0;  // distance from a vertex to the nearest point of the seat band
        if (const auto* l = std::get_if<optics::LensPart>(&*plane.part)) {
            slot.round = true;
            slot.label = plane.part_name;
            slot.width = define(n + "_diameter", l->diameter);
            slot.height = slot.width;
            band_radius = l->diameter / 2 - profile.seat;
            if (band_radius <= 0) fail(plane, "the lens is no larger than its seat (" + format_mm(profile.seat) + " mm)");
        } else {
            const auto& a = std::get<optics::LensletArrayPart>(*plane.part);
            slot.array = &a;
            slot.label = plane.part_name;
            double hx = 0, hy = 0;
            const optics::Lattice& lat = a.lattice;
            const double cell_hy = lat.kind() == optics::LatticeKind::Hexagonal ? lat.pitch_x() / std::sqrt(3.0) : lat.pitch_y() / 2;
            for (int j = 0; j < lat.count_y(); ++j)
                for (const int i : {0, lat.count_x() - 1}) {
                    const Eigen::Vector2d c = lat.center({i, j});
                    hx = std::max(hx, std::abs(c.x()) + lat.pitch_x() / 2);
                    hy = std::max(hy, std::abs(c.y()) + cell_hy);
                }
            define(n + "_pitch_x", lat.pitch_x(), "lenslet spacing along x");
            define(n + "_pitch_y", lat.pitch_y(), "row spacing along y");
            define(n + "_count_x", lat.count_x());
            define(n + "_count_y", lat.count_y());
            slot.width = define(n + "_width", 2 * hx, "the array's outline");
            slot.height = define(n + "_height", 2 * hy);
            const double inradius = lat.kind() == optics::LatticeKind::Hexagonal
                                        ? lat.pitch_x() / 2
                                        : std::min(lat.pitch_x(), lat.pitch_y()) / 2;
            band_radius = std::max(0.0, inradius - profile.seat);
        }
        const Expr rim = define(n + "_seat_sag", sag_at(*lens, band_radius),
                                "depth of the curved face where the seat band begins");
        const double half_w = slot.width.value / 2 - profile.seat, half_h = slot.height.value / 2 - profile.seat;
        slot.clear = Eigen::Vector2d(half_w, half_h);
        if (plane.arrangement == Arrangement::BackToBack) {
            slot.label += " pair, pattern between the flats";
            slot.z0 = define(n + "_pocket_front", z - sheets * film / 2 - thickness + rim,
                             "the front array's outer lenslets rest here");
            slot.z1 = define(n + "_pocket_back", z + sheets * film / 2 + thickness - rim + clearance);
            slot.seat_z = slot.z0.value;
            slot.seat_at_front = true;
            slot.seat_what = "the front array's outer lenslets, " + format_mm(lens->center_thickness - rim.value) +
                             " mm in front of its flat (the pattern in plane " + n + ")";
        } else if (plane.curved_side == CurvedSide::Light) {
            slot.z0 = define(n + "_pocket_front", z + rim - clearance);
            slot.z1 = define(n + "_pocket_back", z + thickness, "the flat back rests here");
            slot.seat_z = slot.z1.value;
            slot.seat_what = "the flat back";
        } else {
            slot.z0 = define(n + "_pocket_front", z, "the flat front rests here");
            slot.z1 = define(n + "_pocket_back", z + thickness - rim + clearance);
            slot.seat_z = slot.z0.value;
            slot.seat_at_front = true;
            slot.seat_what = "the flat front";
        }
        return slot;
    }

    void collect_slots() {
        for (const optics::Plane& plane : design.planes) {
            if (!plane.part) continue;
            Slot slot = slot_for(plane);
            if (!slots.empty() && slots.back().sheets && slot.sheets &&
                std::abs(slots.back().z1.value - slot.z0.value) < 1e-6) {
                // Touching sheets share one pocket.
                Slot& stack = slots.back();
                stack.planes.push_back(&plane);
                stack.name += plane.name;
                stack.label += ", " + plane.part_name;
                stack.z1 = slot.z1;
                continue;
            }
            slots.push_back(std::move(slot));
        }
        for (Slot& s : slots) {
            if (!s.sheets) continue;
            // The pattern lies on the front face of a sheet: the transparencies go in front of it.
            const bool pattern_on_face = s.planes.front()->pattern;
            holder.parameters.group("Sheet stack " + s.name);
            Expr front = s.z0;
            if (pattern_on_face) front = front - sheets * film;
            Expr back = s.z1;
            if (design.kind == DesignKind::I && profile.privacy_filter > 0)
                back = back + define("privacy_filter", profile.privacy_filter, "3M privacy filter behind the diffuser");
            s.z0 = define(s.name + "_pocket_front", front, pattern_on_face ? "the pattern sheets rest here, the pattern face of " + s.planes.front()->name + " behind them" : "the stack rests here");
            s.z1 = define(s.name + "_pocket_back", back + clearance);
            s.seat_z = s.z0.value;
            s.seat_at_front = true;
            s.seat_what = pattern_on_face ? "the front pattern sheet (the pattern face of plane " + s.planes.front()->name +
                                                 " lies pattern_sheets x film behind it)"
                                          : "the front sheet";
            s.label = "sheets " + s.label + (pattern_on_face ? " (pattern sheets in front)" : "");
        }
        for (std::size_t k = 1; k < slots.size(); ++k) {
            const double gap = slots[k].z0.value - slots[k - 1].z1.value;
            if (gap < 0)
                fail(*slots[k].planes.front(), "the pocket of plane " + slots[k].name + " overlaps the pocket of plane " +
                                                   slots[k - 1].name + " by " + format_mm(-gap) + " mm");
            if (gap < profile.min_feature_z)
                fail(*slots[k].planes.front(), "planes " + slots[k - 1].name + " and " + slots[k].name + " leave " +
                                                   format_mm(gap) + " mm between their pockets; the printer needs " +
                                                   format_mm(profile.min_feature_z) + " mm (min_feature_z_mm)");
        }
    }

    ClearAperture aperture_of(const Slot& s) const {
        ClearAperture a;
        a.plane = s.name;
        if (s.round) {
            a.kind = ClearAperture::Kind::Circle;
            a.radius = s.width.value / 2 - profile.seat;
            return a;
        }
        a.half_width = s.width.value / 2 - profile.seat;
        a.half_height = s.height.value / 2 - profile.seat;
        if (s.array && design.kind == DesignKind::I) {
            a.kind = ClearAperture::Kind::WholeCells;
            a.lattice = s.array->lattice;
            a.notch = corner_notch(s.array->lattice);
        } else if (s.array && design.kind == DesignKind::II && profile.baffle > 0 && &s == &slots.front()) {
            a.kind = ClearAperture::Kind::InsetCells;
            a.lattice = s.array->lattice;
            a.inset = profile.baffle / 2;
            a.half_width = s.width.value / 2 - a.inset;
            a.half_height = s.height.value / 2 - a.inset;
        }
        return a;
    }

    // Design I's corner sight windows: one square per quadrant covering the corner lenslet
    // there (the registration lenslets of thesis 8.4.1), mirrored so all four are covered.
    std::array<double, 3> corner_notch(const optics::Lattice& lat) const {
        const double hx = lat.pitch_x() / 2, hy = lat.pitch_x() / std::sqrt(3.0);
        double x0 = 1e300, x1 = 0, y0 = 1e300, y1 = 0;
        for (const optics::CellIndex c : {optics::CellIndex{0, 0}, {lat.count_x() - 1, 0}, {0, lat.count_y() - 1},
                                          {lat.count_x() - 1, lat.count_y() - 1}}) {
            const Eigen::Vector2d p = lat.center(c).cwiseAbs();
            x0 = std::min(x0, p.x() - hx), x1 = std::max(x1, p.x() + hx);
            y0 = std::min(y0, p.y() - hy), y1 = std::max(y1, p.y() + hy);
        }
        const double half = std::max(x1 - x0, y1 - y0) / 2 + profile.beam_margin;
        return {(x0 + x1) / 2, (y0 + y1) / 2, half};
    }

    // The square (centre x, y and half side, in the +x +y quadrant) that the light of the
    // four corner lenslets crosses between z0 and z1, mirrored into one quadrant.
    std::array<double, 3> corner_sight(const std::vector<BeamPath>& paths, double z0, double z1) const {
        const optics::Lattice& lat = slots.front().array->lattice;
        std::vector<Eigen::Vector2d> corners;
        for (const optics::CellIndex c : {optics::CellIndex{0, 0}, {lat.count_x() - 1, 0}, {0, lat.count_y() - 1},
                                          {lat.count_x() - 1, lat.count_y() - 1}})
            corners.push_back(lat.center(c));
        double x0 = 1e300, x1 = 0, y0 = 1e300, y1 = 0;
        for (const BeamPath& path : paths) {
            if (std::none_of(corners.begin(), corners.end(), [&](const Eigen::Vector2d& c) { return (c - path.cell_centre).norm() < 1e-9; }))
                continue;
            const int steps = static_cast<int>(std::ceil((z1 - z0) / 0.05));
            for (int k = 0; k <= steps; ++k) {
                for (std::size_t q = 0; q + 1 < path.points.size(); ++q) {
                    const double z = z0 + (z1 - z0) * k / steps;
                    const Eigen::Vector3d& a = path.points[q];
                    const Eigen::Vector3d& b = path.points[q + 1];
                    if (z < a.z() || z > b.z() || b.z() <= a.z()) continue;
                    const Eigen::Vector2d p = (a + (b - a) * ((z - a.z()) / (b.z() - a.z()))).head<2>().cwiseAbs();
                    x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x());
                    y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
                    break;
                }
            }
        }
        RFD_CHECK(x1 > 0);
        const double half = std::max(x1 - x0, y1 - y0) / 2 + profile.beam_margin;
        return {(x0 + x1) / 2, (y0 + y1) / 2, half};
    }

    Section prism(const std::string& module, const std::string& comment, Expr z0, Expr z1, bool round, Expr w, Expr h) {
        Section s;
        s.kind = round ? Section::Kind::Circle : Section::Kind::Rect;
        s.module = module;
        s.comment = comment;
        s.z0 = z0, s.z1 = z1;
        s.width = s.width1 = w;
        s.height = s.height1 = h;
        if (round) s.facets = circle_facets(w.value, profile.circle_tolerance);
        return s;
    }

    // A channel for the light between z0 and z1: the traced envelope at both ends plus the
    // margin, and never less than `least0` / `least1` (half-sizes: the clear apertures of the
    // parts on either side, which rays may reach anywhere).
    Section channel(const std::string& module, const std::string& comment, Expr z0, Expr z1, bool round,
                    const std::vector<BeamPath>& paths, Eigen::Vector2d least0, Eigen::Vector2d least1) {
        const Envelope e0 = envelope_at(paths, z0.value + 1e-6, false), e1 = envelope_at(paths, z1.value - 1e-6, false);
        const Envelope mid = envelope_over(paths, z0.value, z1.value, false);
        Section s = prism(module, comment, z0, z1, round, 0, 0);
        s.overlap_front = s.overlap_back = true;
        Eigen::Vector2d h0(std::max(e0.x, least0.x()), std::max(e0.y, least0.y()));
        Eigen::Vector2d h1(std::max(e1.x, least1.x()), std::max(e1.y, least1.y()));
        if (round) {
            h0 = Eigen::Vector2d::Constant(std::max(e0.r, least0.maxCoeff()));
            h1 = Eigen::Vector2d::Constant(std::max(e1.r, least1.maxCoeff()));
        }
        // The envelope is not linear in z where the light crosses a focus: if the middle
        // needs more than the frustum gives, use a prism of the largest size.
        const Eigen::Vector2d middle = round ? Eigen::Vector2d::Constant(mid.r) : Eigen::Vector2d(mid.x, mid.y);
        if ((middle.array() > h0.cwiseMax(h1).array() + 1e-9).any()) h0 = h1 = h0.cwiseMax(h1).cwiseMax(middle);
        s.width = Expr(2 * h0.x()) + 2 * margin;
        s.height = Expr(2 * h0.y()) + 2 * margin;
        s.width1 = Expr(2 * h1.x()) + 2 * margin;
        s.height1 = Expr(2 * h1.y()) + 2 * margin;
        if (h0 == h1) s.width1 = s.width, s.height1 = s.height;
        if (round) s.facets = circle_facets(std::max(s.width.value, s.width1.value), profile.circle_tolerance);
        return s;
    }

    Section pocket(const Slot& s) {
        const Expr w = s.width + 2 * clearance, h = s.height + 2 * clearance;
        return prism("pocket_" + s.name, "Pocket of plane " + s.name + ": " + s.label + "; seat: " + s.seat_what + ".",
                     s.z0, s.z1, s.round, w, h);
    }

    // Design II: baffles between the lenslets from the primary array toward the pattern,
    // thinned in steps as the light of each lenslet converges toward its focus.
    std::vector<Section> baffles(const Slot& a, const Slot& b, const std::vector<BeamPath>& paths) {
        const optics::Lattice& lat = a.array->lattice;
        const double length = b.z0.value - a.z1.value;
        const int steps = std::max(1, std::min(4, static_cast<int>(length / std::max(profile.min_feature_z, 1.0))));
        std::vector<Section> out;
        for (int k = 0; k < steps; ++k) {
            const Expr z0 = a.z1 + (b.z0 - a.z1) * (static_cast<double>(k) / steps);
            const Expr z1 = a.z1 + (b.z0 - a.z1) * (static_cast<double>(k + 1) / steps);
            const Envelope cell = envelope_over(paths, z0.value, z1.value, true);
            const Envelope all = envelope_over(paths, z0.value, z1.value, false);
            double hole_x = 2 * (cell.x + profile.beam_margin), hole_y = 2 * (cell.y + profile.beam_margin);
            // A wall the nozzle cannot lay is left out: the holes of that row or column merge.
            if (lat.pitch_x() - hole_x < profile.nozzle) hole_x = lat.pitch_x();
            if (lat.pitch_y() - hole_y < profile.nozzle) hole_y = lat.pitch_y();
            Section s;
            s.kind = Section::Kind::Cells;
            s.module = "baffles_" + std::to_string(k + 1);
            s.comment = "Baffles between the lenslets of " + a.name + ", step " + std::to_string(k + 1) + " of " +
                        std::to_string(steps) + ": walls " + format_mm(lat.pitch_x() - hole_x) + " x " +
                        format_mm(lat.pitch_y() - hole_y) + " mm, as thick as the converging light allows.";
            s.z0 = z0, s.z1 = z1;
            s.width = s.width1 = hole_x;
            s.height = s.height1 = hole_y;
            s.cells = lat;
            s.cells_prefix = a.name;
            // Each step reaches into the next, wider one (and the first into the pocket).
            s.overlap_front = k == 0;
            s.overlap_back = true;
            s.clip = std::array<Expr, 2>{Expr(2 * all.x) + 2 * margin, Expr(2 * all.y) + 2 * margin};
            out.push_back(std::move(s));
        }
        return out;
    }

    // Design III: a conical bore from the main lens to the field lens, with saw-tooth
    // light-trap grooves cut into its wall.
    Section grooved_bore(const Slot& a, const Slot& b, const std::vector<BeamPath>& paths) {
        const double za = a.z1.value, zb = b.z0.value;
        const Envelope e0 = envelope_at(paths, za + 1e-6, false), e1 = envelope_at(paths, zb - 1e-6, false);
        double r0 = e0.r + profile.beam_margin, r1 = e1.r + profile.beam_margin;
        // The cone must hold the whole envelope: raise both ends by the largest shortfall.
        double shortfall = 0.0;
        for (int k = 0; k <= 64; ++k) {
            const double z = za + (zb - za) * k / 64;
            const double need = envelope_at(paths, z, false).r + profile.beam_margin;
            shortfall = std::max(shortfall, need - (r0 + (r1 - r0) * k / 64));
        }
        r0 += shortfall, r1 += shortfall;
        // Few deep grooves rather than many shallow ones: OpenSCAD's CGAL subtracts the bore
        // in time proportional to its facets, and Design IV cuts it 98 times (a 1 mm groove
        // every 3 mm took 91 s to build).
        const double depth = 1.5, pitch = 6.0;
        Section s;
        s.kind = Section::Kind::Revolved;
        s.module = "bore_" + a.name + b.name;
        s.comment = "Bore from " + a.name + " to " + b.name + ": a cone around the light of the field of view, with "
                    "saw-tooth light-trap grooves " + format_mm(depth) + " mm deep every " + format_mm(pitch) +
                    " mm that catch light scattered off the wall.";
        // The bore is circumscribed, so it clears the light with any number of facets; more
        // only shave its corners. Corners within a quarter of the beam margin will do.
        s.facets = circle_facets(2 * (r1 + depth), std::max(profile.circle_tolerance, profile.beam_margin / 4));
        const Expr zA = a.z1 - eps, zB = b.z0 + eps;
        auto cone = [&](double z) { return r0 + (r1 - r0) * (z - za) / (zb - za); };
        s.profile.push_back({Expr(0.0), zA});
        s.profile.push_back({Expr(r0), zA});
        const int teeth = static_cast<int>((zb - za - 2 * pitch) / pitch);
        for (int k = 0; k < teeth; ++k) {
            const double z = za + pitch * (k + 1);
            s.profile.push_back({Expr(cone(z)), a.z1 + pitch * (k + 1)});
            s.profile.push_back({Expr(cone(z) + depth), a.z1 + pitch * (k + 1)});
        }
        s.profile.push_back({Expr(r1), zB});
        s.profile.push_back({Expr(0.0), zB});
        s.z0 = zA, s.z1 = zB;
        return s;
    }

    void build() {
        globals();
        collect_slots();
        RFD_CHECK(!slots.empty());
        const bool angular = design.kind == DesignKind::III || design.kind == DesignKind::IV;

        holder.parameters.group("Holder");
        const Expr z_front = holder.z_front = define("z_front", slots.front().z0 - wall, "front face (toward the light)");
        const Expr z_back = holder.z_back = define("z_back", slots.back().z1 + wall, "back face (toward the observer)");

        std::vector<ClearAperture> apertures;
        for (const Slot& s : slots)
            if (!s.sheets) apertures.push_back(aperture_of(s));
        const BeamSampling sampling{11, 16};
        const std::optional<double> z_exit = angular ? std::optional<double>(z_back.value) : std::nullopt;
        // Design I's corner lenslets are seen through their own sight windows: the window
        // and channels are sized without them, the sheets and the sights with them.
        std::vector<ClearAperture> without_corners = apertures;
        for (ClearAperture& a : without_corners) a.notch.reset();
        const std::vector<BeamPath> paths = beam_paths(design, without_corners, z_front.value, z_exit, sampling);
        const std::vector<BeamPath> all_paths =
            design.kind == DesignKind::I ? beam_paths(design, apertures, z_front.value, z_exit, sampling) : paths;
        if (paths.empty()) fail(design.planes.front(), "no light of the field of view passes the clear apertures");
        holder.fov_half_deg = field_of_view_half_deg(design);

        // Sheets are cut to the light they must catch, plus a seat all round.
        for (Slot& s : slots) {
            if (!s.sheets) continue;
            const Envelope e = envelope_over(all_paths, s.z0.value, s.z1.value, false);
            holder.parameters.group("Sheet stack " + s.name);
            s.width = define(s.name + "_width", std::ceil(2 * (e.x + profile.beam_margin + profile.seat) * 10) / 10, "cut the sheets to this size");
            s.height = define(s.name + "_height", std::ceil(2 * (e.y + profile.beam_margin + profile.seat) * 10) / 10);
            ClearAperture a;
            a.plane = s.name;
            a.half_width = s.width.value / 2 - profile.seat;
            a.half_height = s.height.value / 2 - profile.seat;
            s.clear = Eigen::Vector2d(a.half_width, a.half_height);
            apertures.push_back(a);
        }
        holder.apertures = apertures;

        // Sections front to back.
        auto& sec = holder.sections;
        const Slot& first = slots.front();
        // Rays reach the front face up to the clear aperture plus the field of view's slope
        // times their way from the face to where they meet the part's rim (a lens's dome
        // may stand in front of the holder).
        const double slope = std::tan(holder.fov_half_deg * std::numbers::pi / 180);
        const double z_rim = std::max(design.planes.front().z, first.z0.value + profile.clearance);
        const Eigen::Vector2d at_face = first.clear.array() + (z_rim - z_front.value) * slope;
        const Eigen::Vector2d at_pocket = first.clear.array() + (z_rim - first.z0.value) * slope;
        sec.push_back(channel("front_window", "Window in the front wall, widening toward the light.", z_front, first.z0,
                              first.round, paths, at_face, at_pocket));
        for (std::size_t k = 0; k < slots.size(); ++k) {
            sec.push_back(pocket(slots[k]));
            if (k + 1 == slots.size()) break;
            const Slot& a = slots[k];
            const Slot& b = slots[k + 1];
            if (design.kind == DesignKind::II && a.array && k == 0 && profile.baffle > 0) {
                for (Section& s : baffles(a, b, paths)) sec.push_back(std::move(s));
            } else if (a.round && b.round && b.z0.value - a.z1.value > 10.0) {
                sec.push_back(grooved_bore(a, b, paths));
            } else {
                sec.push_back(channel("channel_" + a.name + "_" + b.name, "Light channel from " + a.name + " to " + b.name + ".",
                                      a.z1, b.z0, a.round && b.round, paths, a.clear, b.clear));
            }
        }
        const Slot& last = slots.back();
        if (angular) {
            // The projection lenslets send light out steeply, from anywhere in their clear
            // aperture: open the window for the steepest traced slope (and a fifth more,
            // for the rays between the traced ones) over the back wall.
            Eigen::Vector2d slope_out = Eigen::Vector2d::Zero();
            for (const BeamPath& path : paths) {
                const Eigen::Vector3d d = path.points.back() - path.points[path.points.size() - 2];
                if (d.z() > 0) slope_out = slope_out.cwiseMax(d.head<2>().cwiseAbs() / d.z());
            }
            const Eigen::Vector2d exit_at_face = last.clear + 1.2 * (z_back.value - last.z1.value + profile.clearance) * slope_out;
            sec.push_back(channel("back_window", "Window in the back wall, widening toward the observer.", last.z1, z_back,
                                  false, paths, last.clear, exit_at_face));
        } else {
            // The observer looks at the diffuser: the window shows all of its lit area.
            Section s = prism("back_window", "Window in the back wall over the diffuser's lit area.", last.z1, z_back,
                              false, last.width - 2 * seat, last.height - 2 * seat);
            s.overlap_front = s.overlap_back = true;
            sec.push_back(std::move(s));
        }
        if (design.kind == DesignKind::I) {
            const std::array<double, 3> sight = corner_sight(all_paths, z_front.value, slots[1].z0.value);
            holder.parameters.group("Registration (thesis 8.4.1)");
            CornerNotches notches{define("sight_x", sight[0], "corner sight windows over the four registration lenslets"),
                                  define("sight_y", sight[1]), define("sight_size", 2 * sight[2])};
            Section s = prism("corner_sights", "Four corner sight windows, through the front wall to the pattern sheets, "
                              "over the corner lenslets that carry the registration markers.",
                              z_front, slots[1].z0, false, 0, 0);
            s.notches = notches;
            s.overlap_front = s.overlap_back = true;
            sec.push_back(std::move(s));
        }
        check_seats_keep_a_band();
        outer_and_parts();
        seats();
    }

    // The section beside a slot's seat face, at that face.
    const Section* beside_seat(const Slot& s) const {
        for (const Section& c : holder.sections) {
            if (c.module == "pocket_" + s.name || c.module == "corner_sights") continue;
            if (s.seat_at_front ? std::abs(c.z1.value - s.z0.value) < 1e-9 || std::abs(c.z1.value - s.z0.value - eps.value) < 1e-9
                                : std::abs(c.z0.value - s.z1.value) < 1e-9 || std::abs(c.z0.value - s.z1.value + eps.value) < 1e-9)
                return &c;
        }
        return nullptr;
    }

    static double half_height_at(const Section& c, double z) {
        if (c.kind == Section::Kind::Revolved) {
            double r = 0;
            for (const auto& p : c.profile)
                if (std::abs(p[1].value - z) < 0.02) r = std::max(r, p[0].value);
            return r / std::cos(std::numbers::pi / c.facets);
        }
        const double t = c.z1.value > c.z0.value ? std::clamp((z - c.z0.value) / (c.z1.value - c.z0.value), 0.0, 1.0) : 0.0;
        if (c.kind == Section::Kind::Cells) return (*c.clip)[1].value / 2;
        const double h = (c.height.value + t * (c.height1.value - c.height.value)) / 2;
        return c.kind == Section::Kind::Circle ? h / std::cos(std::numbers::pi / c.facets) : h;
    }

    void check_seats_keep_a_band() {
        for (const Slot& s : slots) {
            const Section* c = beside_seat(s);
            RFD_CHECK(c != nullptr);
            const double channel = half_height_at(*c, s.seat_at_front ? s.z0.value : s.z1.value);
            const double part = s.height.value / 2;
            if (c->kind != Section::Kind::Cells && channel > part - profile.nozzle)
                fail(*s.planes.front(), "the light of the field of view needs " + format_mm(2 * channel) +
                                            " mm at the seat of plane " + s.name + ", which leaves no seat under the part (" +
                                            format_mm(2 * part) + " mm)");
        }
    }

    void outer_and_parts() {
        double half_w = 0, half_h = 0;
        Expr widest = 0, tallest = 0;
        for (const Section& c : holder.sections) {
            double w = 0, h = c.half_height_max();
            switch (c.kind) {
            case Section::Kind::Rect: w = std::max(c.width.value, c.width1.value) / 2; break;
            case Section::Kind::Cells: w = (*c.clip)[0].value / 2; break;
            default: w = h; break;
            }
            if (c.notches) w = std::max(w, c.notches->x.value + c.notches->size.value / 2);
            half_w = std::max(half_w, w), half_h = std::max(half_h, h);
        }
        holder.parameters.group("Holder");
        const Expr cell_w = define("cavity_width", std::ceil(2 * half_w * 100) / 100, "widest cut of the cavity");
        const Expr cell_h = define("cavity_height", std::ceil(2 * half_h * 100) / 100);
        if (design.macro) {
            const optics::MacroGrid& m = *design.macro;
            holder.parameters.group("Design IV: the grid of Design III cells");
            const Expr nx = define("macro_count_x", m.count_x), ny = define("macro_count_y", m.count_y);
            const Expr px = define("macro_pitch_x", m.pitch_x), py = define("macro_pitch_y", m.pitch_y);
            for (const auto& [pitch, cavity, axis] : {std::tuple{m.pitch_x, cell_w.value, "x"}, std::tuple{m.pitch_y, cell_h.value, "y"}})
                if (pitch - cavity < profile.min_wall)
                    fail(design.planes.front(), std::string("the cell's widest pocket with its walls (") + format_mm(cavity) + " + " +
                                                    format_mm(profile.min_wall) + " mm) is larger than the macro-pixel pitch along " +
                                                    axis + " (" + format_mm(pitch) + " mm)");
            holder.cell_grid = std::array<Expr, 4>{nx, ny, px, py};
            holder.width = define("outer_width", (nx - 1) * px + cell_w + 2 * wall);
            holder.height = define("outer_height", (ny - 1) * py + cell_h + 2 * wall);
            for (int j = 0; j < m.count_y; ++j)
                for (int i = 0; i < m.count_x; ++i)
                    holder.cells.emplace_back((i - (m.count_x - 1) / 2.0) * m.pitch_x, (j - (m.count_y - 1) / 2.0) * m.pitch_y);
            // Plates split through the centres of the cell rows: each middle plate carries the
            // upper halves of one row and the lower halves of the next.
            const Expr row0 = -((ny - 1) / 2) * py;
            holder.parts.push_back({"bottom", -holder.height / 2, row0, 1, "print lying on its outer face, cavities up"});
            holder.parts.push_back({"middle", row0, row0 + py, m.count_y - 1,
                                    "print " + std::to_string(m.count_y - 1) + " of these, each lying on its lower face"});
            holder.parts.push_back({"top", -row0, holder.height / 2, 1, "print lying on its outer face, cavities up"});
        } else {
            holder.cells.emplace_back(0.0, 0.0);
            holder.width = define("outer_width", cell_w + 2 * wall);
            holder.height = define("outer_height", cell_h + 2 * wall);
            holder.parts.push_back({"base", -holder.height / 2, 0, 1, "print lying on its outer face, pockets up"});
            holder.parts.push_back({"lid", 0, holder.height / 2, 1, "print lying on its outer face, pockets up"});
        }
    }

    void seats() {
        // Probe each seat in the lower half of the centre-most cell of the first printed part
        // above the bottom (Design IV: the middle plate) or the base.
        Eigen::Vector2d cell = holder.cells.front();
        if (design.macro) {
            const double row1 = holder.parts[1].y1.value;
            cell = Eigen::Vector2d(holder.cells[static_cast<std::size_t>(design.macro->count_x / 2)].x(), row1);
        }
        for (const Slot& s : slots) {
            const Section* c = beside_seat(s);
            const double z = s.seat_at_front ? s.z0.value : s.z1.value;
            Eigen::Vector2d probe;
            if (c->kind == Section::Kind::Cells) {
                // On a wall between lenslets, where the baffles meet the seat.
                const optics::Lattice& lat = c->cells;
                probe = Eigen::Vector2d(lat.count_x() % 2 == 0 ? 0.0 : lat.pitch_x() / 2,
                                        lat.count_y() % 2 == 0 ? -lat.pitch_y() : -lat.pitch_y() / 2);
            } else {
                const double pocket = s.height.value / 2 + profile.clearance;
                probe = Eigen::Vector2d(0.0, -(pocket + half_height_at(*c, z)) / 2);
            }
            Seat face;
            face.plane = s.name;
            face.what = s.seat_what;
            face.z = s.seat_z;
            face.probe = cell + probe;
            face.probe_from_z = (s.z0.value + s.z1.value) / 2;
            holder.seats.push_back(face);
        }
    }
};

}  // namespace

Holder make_holder(const optics::Design& design, const HolderProfile& profile, const PatternFilm& film) {
    RFD_CHECK(film.sheets == 1 || film.sheets == 2);
    Builder b{design, profile, film, {}, {}, {}, {}, {}, {}, {}, {}, {}};
    b.holder.design_name = design.name;
    b.holder.design_kind = std::string(optics::to_string(design.kind));
    b.build();
    Holder& h = b.holder;
    switch (design.kind) {
    case DesignKind::I:
        h.title = "Frame for Design I: lens array, pattern sheets, spacer and diffuser, in register";
        break;
    case DesignKind::II:
        h.title = "Housing for Design II (thesis figure 8.9): primary array, baffles, corrective pair with the pattern, diffuser";
        break;
    case DesignKind::III:
        h.title = "Tube for Design III (thesis figure 8.12): main lens, field lens, meso, pattern and projection arrays";
        break;
    case DesignKind::IV:
        h.title = "Block for Design IV: a grid of Design III cells (thesis figure 8.14)";
        break;
    }
    h.notes.push_back("Assembly: lay each part into its pocket in the lower part, pressed against its seat,");
    h.notes.push_back("then close the upper part over it. Seats (the face each part must rest on):");
    for (const Seat& s : h.seats)
        h.notes.push_back("  plane " + s.plane + ": " + s.what + " at z = " + format_mm(s.z) + " mm");
    for (const PrintedPart& p : h.parts)
        h.notes.push_back("Part \"" + p.name + "\"" + (p.copies > 1 ? " (x" + std::to_string(p.copies) + ")" : "") + ": " + p.print_note + ".");
    return h;
}

}  // namespace rfd::holders
