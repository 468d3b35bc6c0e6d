#pragma once
// A display design (thesis chapter 8, Designs I-IV) as typed data, read from a design file
// (docs/formats.md; presets in designs/). Lengths in millimetres, angles in degrees.
//
// A design is a row of planes named as in the thesis's ray diagrams (A, B, C, ...) along
// the optical axis z (the direction light travels; see surface.hpp). Each plane may hold
// one part (a single lens, a lenslet array or a flat sheet), may be the pattern plane, and
// may be the diffuser. A plane's z is:
//   - single lens or array: the vertex of the surface that faces the light;
//   - back-to-back pair of arrays: the shared flat between them (where the pattern lies);
//   - sheet: its face toward the light.
// Parts are described once in [parts.NAME] and placed by name.

#include <filesystem>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "core/error.hpp"
#include "core/units.hpp"
#include "optics/lattice.hpp"
#include "optics/system.hpp"

namespace rfd::optics {

enum class DesignKind { I, II, III, IV };
std::string_view to_string(DesignKind kind);
/// Designs III and IV show their picture to an observer, not on a diffuser.
inline bool is_observer_variant(DesignKind kind) { return kind == DesignKind::III || kind == DesignKind::IV; }

/// A plano-convex (or conic-convex) lens: one curved surface and one flat.
struct PlanoConvex {
    double radius = 0.0;             ///< radius of the curved surface, mm, > 0
    double conic = 0.0;              ///< conic constant of the curved surface
    double center_thickness = 0.0;   ///< mm
    double index = 1.5;
    std::string material;            ///< catalogue name, or "" when given as an index
    double nominal_focal_length = 0.0;  ///< as the maker states it; checked against the rest
};

struct LensPart {
    PlanoConvex lens;
    double diameter = 0.0;  ///< mm
};

struct LensletArrayPart {
    PlanoConvex lens;  ///< one lenslet
    Lattice lattice;
};

struct SheetPart {
    double thickness = 0.0;  ///< mm
    double index = 1.5;
    std::string material;
};

using Part = std::variant<LensPart, LensletArrayPart, SheetPart>;

enum class CurvedSide { Light, Observer };
enum class Arrangement { Single, BackToBack };

struct Plane {
    std::string name;                ///< "A", "B", ...
    double z = 0.0;                  ///< mm, see the header comment
    std::optional<Part> part;
    std::string part_name;
    CurvedSide curved_side = CurvedSide::Light;
    Arrangement arrangement = Arrangement::Single;
    bool pattern = false;            ///< the printed transparency lies in this plane
    bool diffuser = false;           ///< this plane's sheet scatters (Designs I and II)
    std::string role;                ///< free text from the file, e.g. "primary lens array"
    SourceLocation where;            ///< the [planes.X] table, for messages
};

struct Printer {
    Dpi dpi_x{2880};
    Dpi dpi_y{1440};
};

/// Design IV: a grid of Design III macro-pixels.
struct MacroGrid {
    int count_x = 1, count_y = 1;
    double pitch_x = 0.0, pitch_y = 0.0;  ///< mm
};

struct Design {
    std::string file;
    std::string name;
    DesignKind kind = DesignKind::I;
    std::string description;
    Printer printer;
    std::vector<Plane> planes;  ///< sorted by z
    std::optional<MacroGrid> macro;

    const Plane& pattern_plane() const;
    const Plane* diffuser_plane() const;
    const Plane& plane(const std::string& name) const;
};

/// Reads and checks a design file. Every key is checked: unknown or missing keys, wrong
/// units and impossible geometry (cell corners outside the lens sphere, overlapping planes,
/// negative distances) throw InputError naming the file, line and key.
Design load_design(const std::filesystem::path& path);
Design parse_design(std::string_view toml_text, const std::string& name);

/// The design with every lenslet array (they share one lattice) resized to count_x by
/// count_y lenslets, same pitch, lenslets, planes and printer: a smaller copy of a preset
/// for tests and benchmarks, or a wider one around a lenslet.
Design with_lenslet_count(Design design, int count_x, int count_y);

/// Effective focal length of a plano-convex lens in air: R / (n - 1).
double focal_length(const PlanoConvex& lens);

/// The design as a sequential system for one lenslet column through the display, from
/// the first surface to the diffuser (or the last part). Surface labels: "A front",
/// "A back" (or "A flat"), "B pattern", "C diffuser", ... The pattern plane and the
/// diffuser are bookkeeping surfaces (no refraction) when they lie inside a part.
SequentialSystem build_system(const Design& design);

/// Axial extent [front, back] in z that a plane's part occupies (its sag included).
std::array<double, 2> axial_extent(const Plane& plane);

}  // namespace rfd::optics
