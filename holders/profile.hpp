#pragma once
// What a 3D printer can make, and how the holder meets the parts it holds: the numbers
// every holder and the fit-test coupon are built from. Read from a printer profile
// (`--3d-printer FDM.toml`, holders/profiles/fdm_0.4mm.toml shows every key);
// every key is optional and defaults to a 0.4 mm nozzle FDM printer.
//
//   [printer]
//   name = "..."
//   clearance_mm = 0.2      # radial play of a slip fit (pockets are this much larger)
//   min_wall_mm = 2.0       # thinnest wall that carries load
//   min_feature_z_mm = 0.5  # thinnest layer feature along the print's z (ribs, floors)
//   nozzle_mm = 0.4         # thinnest wall the nozzle can lay (baffles end there)
//   circle_tolerance_mm = 0.01  # largest gap between a printed circle's facets and the circle
//   [holder]
//   seat_mm = 0.8           # how far a seat reaches under the rim of a part
//   baffle_mm = 1.0         # baffle wall between lenslets, at its thickest
//   beam_margin_mm = 0.15   # air kept between the light and the holder
//   privacy_filter_mm = 0   # Design I: a privacy-filter sheet behind the diffuser (0: none)
//
// The printed transparencies the holder keeps room for (their thickness and how many are
// stacked) are the film printer's, not the 3D printer's: PatternFilm, from the printer
// profile that prints the pattern (print/printer.hpp), so the two cannot disagree.
//
// Units: millimetres.

#include <filesystem>
#include <string>

namespace rfd::holders {

struct HolderProfile {
    std::string name = "generic FDM printer, 0.4 mm nozzle";
    double clearance = 0.2;
    double min_wall = 2.0;
    double min_feature_z = 0.5;
    double nozzle = 0.4;
    double circle_tolerance = 0.01;
    double seat = 0.8;
    double baffle = 1.0;
    double beam_margin = 0.15;
    double privacy_filter = 0.0;
};

/// The printed transparencies of a pattern, as the film printer's profile gives them.
struct PatternFilm {
    double thickness = 0.1;  ///< mm, one printed transparency
    int sheets = 1;          ///< transparencies stacked back to back (1 or 2)
};

/// Reads a profile; unknown keys, and values out of their printable ranges, throw
/// InputError naming file, line and key.
HolderProfile load_profile(const std::filesystem::path& path);
HolderProfile parse_profile(std::string_view toml_text, const std::string& name);

/// Facets for a printed circle of diameter d: enough that the circumscribed polygon's
/// corners stand no more than `tolerance` outside the circle (a part seated in the bore
/// touches its flats), at least 32, a multiple of 4 (so the polygon is symmetric about
/// both axes, like the holder). Finer facets only slow OpenSCAD down: an FDM printer does
/// not resolve a hundredth of a millimetre.
int circle_facets(double diameter, double tolerance);

}  // namespace rfd::holders
