#include "optics/design.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/config.hpp"
#include "optics/lens_file.hpp"
#include "core/text.hpp"

namespace rfd::optics {

std::string_view to_string(DesignKind kind) {
    switch (kind) {
        case DesignKind::I: return "I";
        case DesignKind::II: return "II";
        case DesignKind::III: return "III";
        case DesignKind::IV: return "IV";
    }
    return "?";
}

double focal_length(const PlanoConvex& lens) { return lens.radius / (lens.index - 1.0); }

const Plane& Design::pattern_plane() const {
    for (const auto& p : planes)
        if (p.pattern) return p;
    RFD_CHECK_MSG(false, "a loaded design always has a pattern plane");
    return planes.front();
}

const Plane* Design::diffuser_plane() const {
    for (const auto& p : planes)
        if (p.diffuser) return &p;
    return nullptr;
}

const Plane& Design::plane(const std::string& plane_name) const {
    for (const auto& p : planes)
        if (p.name == plane_name) return p;
    throw InputError(SourceLocation{file}, "design has no plane '" + plane_name + "'");
}

namespace {

// Parts closer than this are touching, not overlapping: a plane's z plus a thickness in
// floating point lands a rounding error away from the next plane's z.
constexpr double kTouching = 1e-6;  // mm

// What a design's lengths may be: from a micrometre (below, a print dot is larger than the
// part) to 100 m. Beyond them every figure the optics derive would be 0, huge or NaN.
constexpr double kShortestLength = 1e-3, kLongestLength = 1e5;  // mm
// A nearly flat surface has a radius and focal length far beyond any part's size.
constexpr double kLongestRadius = 1e9;  // mm

double length(ConfigTable& t, const std::string& key) { return t.number(key, kShortestLength, kLongestLength); }
double radius(ConfigTable& t, const std::string& key) { return t.number(key, kShortestLength, kLongestRadius); }

std::array<double, 2> length_pair(ConfigTable& t, const std::string& key) {
    const std::array<double, 2> pair = t.positive_pair(key);
    for (const double value : pair)
        if (value < kShortestLength || value > kLongestLength)
            t.fail(key, "expected lengths from " + format_number(kShortestLength) + " to " +
                            format_number(kLongestLength) + " mm, found " + format_number(value));
    return pair;
}

PlanoConvex read_plano_convex(ConfigTable& t) {
    PlanoConvex lens;
    lens.radius = radius(t, "radius_mm");
    lens.conic = t.optional_number("conic", -1e3, 1e3).value_or(0.0);
    lens.center_thickness = length(t, "center_thickness_mm");
    lens.material = t.optional_string("material").value_or("");
    lens.index = read_medium(t);
    if (lens.index <= 1.0) t.fail(t.has("index") ? "index" : "material", "a lens needs an index above 1");
    lens.nominal_focal_length = radius(t, "focal_length_mm");
    const double computed = focal_length(lens);
    // Makers round their focal lengths; 2% catches a wrong radius, index or unit.
    if (std::abs(computed - lens.nominal_focal_length) > 0.02 * lens.nominal_focal_length)
        t.fail("focal_length_mm", "radius " + format_number(lens.radius, 4) + " mm and index " +
                                      format_number(lens.index, 4) + " give f = R/(n-1) = " +
                                      format_number(computed, 4) + " mm, not " +
                                      format_number(lens.nominal_focal_length, 4) + " mm");
    return lens;
}

// The curved surface must reach `rim` (the aperture radius or the cell corner) and leave
// the lens a positive edge thickness there.
void check_reach(ConfigTable& t, const PlanoConvex& lens, double rim, const std::string& what) {
    const Conic conic{1.0 / lens.radius, lens.conic};
    const auto edge_sag = sag(conic, rim * rim);
    if (!edge_sag)
        t.fail("radius_mm", what + " at " + format_number(rim, 4) + " mm from the axis lie outside the lens "
                            "sphere of radius " + format_number(lens.radius, 4) + " mm");
    if (*edge_sag >= lens.center_thickness)
        t.fail("center_thickness_mm", "the lens is thinner than its sag: edge thickness " +
                                          format_number(lens.center_thickness - *edge_sag, 4) + " mm at " +
                                          what);
}

Lattice read_lattice(ConfigTable& t) {
    const std::string kind = t.choice("lattice", {"hexagonal", "rectangular"});
    const auto count = t.integer_pair("count", 1, 100000);
    if (kind == "hexagonal") {
        double pitch = 0.0;
        if (t.has("lenses_per_cm2")) {
            // A hexagonal cell has area pitch^2 sqrt(3)/2.
            // 1e-4 to 1e6 per cm^2: pitches from about 10 um to 1 m, within the lengths above.
            const double density = t.number("lenses_per_cm2", 1e-4, 1e6);
            pitch = std::sqrt(100.0 / density / (std::sqrt(3.0) / 2.0));
            if (t.has("pitch_mm")) t.fail("pitch_mm", "give either pitch_mm or lenses_per_cm2");
        } else {
            pitch = length(t, "pitch_mm");
        }
        return Lattice::hexagonal(pitch, static_cast<int>(count[0]), static_cast<int>(count[1]));
    }
    const auto pitch = length_pair(t, "pitch_mm");
    return Lattice::rectangular(pitch[0], pitch[1], static_cast<int>(count[0]),
                                static_cast<int>(count[1]));
}

Part read_part(ConfigTable& t) {
    const std::string type = t.choice("type", {"lens", "lenslet_array", "sheet"});
    t.optional_string("source");  // free text: maker, catalogue number, datasheet
    if (type == "lens") {
        LensPart part{read_plano_convex(t), length(t, "diameter_mm")};
        check_reach(t, part.lens, part.diameter / 2, "the rim");
        return part;
    }
    if (type == "lenslet_array") {
        PlanoConvex lens = read_plano_convex(t);
        Lattice lattice = read_lattice(t);
        check_reach(t, lens, lattice.circumradius(), "the cell corners");
        return LensletArrayPart{lens, lattice};
    }
    SheetPart sheet;
    sheet.thickness = length(t, "thickness_mm");
    sheet.material = t.optional_string("material").value_or("");
    sheet.index = read_medium(t);
    return sheet;
}

const PlanoConvex* lens_of(const Part& part) {
    if (const auto* lens = std::get_if<LensPart>(&part)) return &lens->lens;
    if (const auto* array = std::get_if<LensletArrayPart>(&part)) return &array->lens;
    return nullptr;
}

Design build_design(ConfigTable& root) {
    Design design;
    design.file = root.file();
    {
        auto t = root.table("design");
        design.name = t.string("name");
        const std::string kind = t.choice("kind", {"I", "II", "III", "IV"});
        design.kind = kind == "I"    ? DesignKind::I
                      : kind == "II" ? DesignKind::II
                      : kind == "III" ? DesignKind::III
                                      : DesignKind::IV;
        design.description = t.optional_string("description").value_or("");
        t.optional_string("thesis_section");
        t.finish();
    }
    {
        auto t = root.table("printer");
        t.optional_string("name");
        design.printer.dpi_x = Dpi(t.number("dpi_x", 1.0, 100000.0));
        design.printer.dpi_y = Dpi(t.number("dpi_y", 1.0, 100000.0));
        t.finish();
    }
    auto parts_table = root.table("parts");
    std::vector<std::pair<std::string, Part>> parts;
    for (const auto& name : parts_table.keys()) {
        auto t = parts_table.table(name);
        parts.emplace_back(name, read_part(t));
        t.finish();
    }
    parts_table.finish();

    auto planes_table = root.table("planes");
    for (const auto& name : planes_table.keys()) {
        auto t = planes_table.table(name);
        if (name.size() != 1 || name[0] < 'A' || name[0] > 'Z')
            planes_table.fail(name, "planes are named with one capital letter as in the thesis (A, B, C, ...)");
        Plane plane;
        plane.name = name;
        plane.where = t.location();
        plane.z = t.number("z_mm", -1e5, 1e5);
        plane.role = t.optional_string("role").value_or("");
        plane.pattern = t.optional_boolean("pattern").value_or(false);
        plane.diffuser = t.optional_boolean("diffuser").value_or(false);
        if (auto part_name = t.optional_string("part")) {
            auto found = std::find_if(parts.begin(), parts.end(),
                                      [&](const auto& p) { return p.first == *part_name; });
            if (found == parts.end()) t.fail("part", "no part named '" + *part_name + "' in [parts]");
            plane.part = found->second;
            plane.part_name = *part_name;
            const bool is_lens = lens_of(*plane.part) != nullptr;
            if (is_lens) {
                const std::string arrangement =
                    t.optional_string("arrangement").value_or("single");
                if (arrangement != "single" && arrangement != "back_to_back")
                    t.fail("arrangement", "expected \"single\" or \"back_to_back\"");
                plane.arrangement = arrangement == "single" ? Arrangement::Single
                                                            : Arrangement::BackToBack;
                if (plane.arrangement == Arrangement::Single) {
                    const std::string side = t.choice("curved_side", {"light", "observer"});
                    plane.curved_side = side == "light" ? CurvedSide::Light : CurvedSide::Observer;
                } else if (t.has("curved_side")) {
                    t.fail("curved_side", "a back-to-back pair has its curved sides outward; "
                                          "curved_side does not apply");
                }
                if (plane.pattern && plane.arrangement == Arrangement::Single)
                    t.fail("pattern", "a pattern can lie in a plane with a lens only between a "
                                      "back-to-back pair (arrangement = \"back_to_back\")");
                if (plane.diffuser) t.fail("diffuser", "a diffuser must be a sheet, not a lens");
            } else if (plane.diffuser && plane.pattern) {
                t.fail("diffuser", "the pattern and the diffuser cannot share a plane");
            }
        } else if (plane.diffuser) {
            t.fail("diffuser", "a diffuser plane needs its sheet: part = \"NAME\"");
        }
        if (!plane.part && !plane.pattern)
            t.fail("part", "a plane needs a part or pattern = true");
        t.finish();
        design.planes.push_back(std::move(plane));
    }
    planes_table.finish();

    if (auto t = root.optional_table("macro")) {
        MacroGrid macro;
        const auto count = t->integer_pair("count", 1, 1000);
        const auto pitch = length_pair(*t, "pitch_mm");
        macro = {static_cast<int>(count[0]), static_cast<int>(count[1]), pitch[0], pitch[1]};
        t->finish();
        design.macro = macro;
        if (design.kind != DesignKind::IV) t->fail("count", "[macro] applies to Design IV only");
        // Every cell must fit its widest part: the lenses and arrays of one macro-pixel.
        double widest_x = 0.0, widest_y = 0.0;
        for (const auto& [name, part] : parts) {
            if (const auto* lens = std::get_if<LensPart>(&part)) {
                widest_x = std::max(widest_x, lens->diameter);
                widest_y = std::max(widest_y, lens->diameter);
            } else if (const auto* array = std::get_if<LensletArrayPart>(&part)) {
                widest_x = std::max(widest_x, 2.0 * array->lattice.half_extent().x());
                widest_y = std::max(widest_y, 2.0 * array->lattice.half_extent().y());
            }
        }
        if (macro.pitch_x < widest_x || macro.pitch_y < widest_y)
            t->fail("pitch_mm", "macro-pixel pitch " + format_number(macro.pitch_x, 4) + " x " +
                                    format_number(macro.pitch_y, 4) + " mm is smaller than the widest part (" +
                                    format_number(widest_x, 4) + " x " + format_number(widest_y, 4) + " mm)");
    } else if (design.kind == DesignKind::IV) {
        root.fail("macro", "Design IV needs a [macro] grid of Design III cells");
    }
    root.finish();

    // Geometry: planes in alphabetical order must lie one after the other along z, and the
    // space each part occupies must not overlap the next.
    auto& planes = design.planes;
    std::sort(planes.begin(), planes.end(),
              [](const Plane& a, const Plane& b) { return a.name < b.name; });
    for (std::size_t k = 1; k < planes.size(); ++k) {
        const Plane& a = planes[k - 1];
        const Plane& b = planes[k];
        if (b.z <= a.z)
            throw InputError(SourceLocation{b.where.file, b.where.line, 0, "planes." + b.name + ".z_mm"},
                             "negative or zero distance from plane " + a.name + " (z = " +
                                 format_number(a.z, 4) + " mm) to plane " + b.name + " (z = " + format_number(b.z, 4) +
                                 " mm): planes must follow in order A, B, C, ... along the light");
        const double overlap = axial_extent(a)[1] - axial_extent(b)[0];
        if (overlap > kTouching)
            throw InputError(SourceLocation{b.where.file, b.where.line, 0, "planes." + b.name + ".z_mm"},
                             "plane " + b.name + " overlaps plane " + a.name + " by " +
                                 format_number(overlap, 4) + " mm (" + a.name + " ends at z = " +
                                 format_number(axial_extent(a)[1], 4) + " mm, " + b.name + " starts at z = " +
                                 format_number(axial_extent(b)[0], 4) + " mm)");
    }
    const auto pattern_count = std::count_if(planes.begin(), planes.end(),
                                             [](const Plane& p) { return p.pattern; });
    if (pattern_count != 1)
        throw InputError(SourceLocation{design.file, 0, 0, "planes"},
                         "a design needs exactly one plane with pattern = true, found " +
                             std::to_string(pattern_count));
    const bool needs_diffuser = design.kind == DesignKind::I || design.kind == DesignKind::II;
    if (needs_diffuser && !design.diffuser_plane())
        throw InputError(SourceLocation{design.file, 0, 0, "planes"},
                         "Designs I and II show their image on a diffuser: mark one sheet with "
                         "diffuser = true");
    // Every lenslet array of a design must share one lattice: lenslet k of one array
    // works with lenslet k of the next.
    const Lattice* first_lattice = nullptr;
    for (const auto& p : planes) {
        if (!p.part) continue;
        const auto* array = std::get_if<LensletArrayPart>(&*p.part);
        if (!array) continue;
        if (!first_lattice) {
            first_lattice = &array->lattice;
        } else if (array->lattice.kind() != first_lattice->kind() ||
                   std::abs(array->lattice.pitch_x() - first_lattice->pitch_x()) > 1e-12 ||
                   std::abs(array->lattice.pitch_y() - first_lattice->pitch_y()) > 1e-12 ||
                   array->lattice.count_x() != first_lattice->count_x() ||
                   array->lattice.count_y() != first_lattice->count_y()) {
            throw InputError(SourceLocation{p.where.file, p.where.line, 0, "planes." + p.name + ".part"},
                             "all lenslet arrays of a design must share one lattice (pitch, count)");
        }
    }
    return design;
}

}  // namespace

std::array<double, 2> axial_extent(const Plane& plane) {
    if (!plane.part) return {plane.z, plane.z};
    if (const auto* sheet = std::get_if<SheetPart>(&*plane.part))
        return {plane.z, plane.z + sheet->thickness};
    const PlanoConvex& lens = *lens_of(*plane.part);
    // The vertex is the part's extreme point on its curved side (convex surfaces).
    if (plane.arrangement == Arrangement::BackToBack)
        return {plane.z - lens.center_thickness, plane.z + lens.center_thickness};
    return {plane.z, plane.z + lens.center_thickness};
}

SequentialSystem build_system(const Design& design) {
    SequentialSystem system;
    system.name = design.name;
    const Lattice* lattice = nullptr;
    for (const auto& p : design.planes)
        if (p.part)
            if (const auto* array = std::get_if<LensletArrayPart>(&*p.part)) {
                lattice = &array->lattice;
                break;
            }
    auto current_index = [&] {
        return system.surfaces.empty() ? system.index_before : system.surfaces.back().index_after;
    };
    for (const auto& p : design.planes) {
        const std::string& n = p.name;
        if (!p.part) {
            // A bare pattern plane in air: bookkeeping only, under the lenslet lattice.
            Aperture aperture = lattice ? Aperture(LatticeAperture{*lattice}) : Aperture(Unbounded{});
            system.surfaces.push_back({Flat{}, aperture, p.z, current_index(), n + " pattern"});
            continue;
        }
        if (const auto* sheet = std::get_if<SheetPart>(&*p.part)) {
            const std::string front = p.pattern ? " pattern" : p.diffuser ? " diffuser" : " front";
            Aperture aperture = Unbounded{};
            if (p.pattern && lattice) aperture = LatticeAperture{*lattice};
            system.surfaces.push_back({Flat{}, aperture, p.z, sheet->index, n + front});
            system.surfaces.push_back({Flat{}, Unbounded{}, p.z + sheet->thickness, 1.0, n + " back"});
            continue;
        }
        const PlanoConvex& lens = *lens_of(*p.part);
        const auto* array = std::get_if<LensletArrayPart>(&*p.part);
        // An array's flat side is one continuous face; a single lens's flat is its disc.
        auto curved_aperture = [&]() -> Aperture {
            if (array) return LatticeAperture{array->lattice};
            return CircularAperture{std::get<LensPart>(*p.part).diameter / 2};
        };
        auto flat_aperture = [&]() -> Aperture {
            if (array) return Unbounded{};
            return curved_aperture();
        };
        const Conic toward_light{1.0 / lens.radius, lens.conic};
        const Conic toward_observer{-1.0 / lens.radius, lens.conic};
        const double ct = lens.center_thickness;
        if (p.arrangement == Arrangement::BackToBack) {
            system.surfaces.push_back({toward_light, curved_aperture(), p.z - ct, lens.index, n + " front"});
            // The pattern between the flats sees the lattice of the lenslet above it.
            system.surfaces.push_back({Flat{}, curved_aperture(), p.z, lens.index,
                                       n + (p.pattern ? " pattern" : " flat")});
            system.surfaces.push_back({toward_observer, curved_aperture(), p.z + ct, 1.0, n + " back"});
        } else if (p.curved_side == CurvedSide::Light) {
            system.surfaces.push_back({toward_light, curved_aperture(), p.z, lens.index, n + " front"});
            system.surfaces.push_back({Flat{}, flat_aperture(), p.z + ct, 1.0, n + " back"});
        } else {
            system.surfaces.push_back({Flat{}, flat_aperture(), p.z, lens.index, n + " front"});
            system.surfaces.push_back({toward_observer, curved_aperture(), p.z + ct, 1.0, n + " back"});
        }
    }
    // A surface that touching planes put a hair (< kTouching) before the surface ahead of
    // it lies on that surface.
    for (std::size_t s = 1; s < system.surfaces.size(); ++s)
        system.surfaces[s].z = std::max(system.surfaces[s].z, system.surfaces[s - 1].z);
    system.validate();
    return system;
}

Design load_design(const std::filesystem::path& path) {
    auto root = ConfigTable::parse_file(path);
    return build_design(root);
}

Design parse_design(std::string_view toml_text, const std::string& name) {
    auto root = ConfigTable::parse_string(toml_text, name);
    return build_design(root);
}

Design with_lenslet_count(Design design, int count_x, int count_y) {
    RFD_CHECK(count_x > 0 && count_y > 0);
    for (Plane& plane : design.planes) {
        if (!plane.part) continue;
        if (auto* array = std::get_if<LensletArrayPart>(&*plane.part)) {
            const Lattice& l = array->lattice;
            array->lattice = l.kind() == LatticeKind::Hexagonal
                                 ? Lattice::hexagonal(l.pitch_x(), count_x, count_y)
                                 : Lattice::rectangular(l.pitch_x(), l.pitch_y(), count_x, count_y);
        }
    }
    return design;
}

}  // namespace rfd::optics
