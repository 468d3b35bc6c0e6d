#include "holders/profile.hpp"

#include <cmath>
#include <numbers>

#include "core/config.hpp"

namespace rfd::holders {
namespace {

HolderProfile read(ConfigTable root) {
    HolderProfile p;
    if (auto t = root.optional_table("printer")) {
        if (auto name = t->optional_string("name")) p.name = *name;
        p.clearance = t->optional_number("clearance_mm", 0.0, 2.0).value_or(p.clearance);
        p.min_wall = t->optional_number("min_wall_mm", 0.4, 20.0).value_or(p.min_wall);
        p.min_feature_z = t->optional_number("min_feature_z_mm", 0.05, 5.0).value_or(p.min_feature_z);
        p.nozzle = t->optional_number("nozzle_mm", 0.05, 2.0).value_or(p.nozzle);
        p.circle_tolerance = t->optional_number("circle_tolerance_mm", 0.001, 1.0).value_or(p.circle_tolerance);
        t->finish();
    }
    if (auto t = root.optional_table("holder")) {
        p.seat = t->optional_number("seat_mm", 0.2, 10.0).value_or(p.seat);
        p.baffle = t->optional_number("baffle_mm", 0.0, 5.0).value_or(p.baffle);
        p.beam_margin = t->optional_number("beam_margin_mm", 0.0, 5.0).value_or(p.beam_margin);
        for (const char* moved : {"film_mm", "pattern_sheets"})
            if (t->has(moved))
                t->fail(moved, "the printed film is the film printer's: set film_mm and sheets in its profile "
                               "(printers/*.toml), which prints the pattern and sizes the holder's pocket");
        p.privacy_filter = t->optional_number("privacy_filter_mm", 0.0, 5.0).value_or(0.0);
        t->finish();
    }
    root.finish();
    if (p.baffle > 0 && p.baffle < p.nozzle)
        root.fail("holder", "baffle_mm (" + std::to_string(p.baffle) +
                                ") is thinner than the nozzle (nozzle_mm): the printer cannot lay it; "
                                "use 0 for no baffles");
    return p;
}

}  // namespace

HolderProfile load_profile(const std::filesystem::path& path) {
    return read(ConfigTable::parse_file(path));
}

HolderProfile parse_profile(std::string_view toml_text, const std::string& name) {
    return read(ConfigTable::parse_string(toml_text, name));
}

int circle_facets(double diameter, double tolerance) {
    // A regular n-gon circumscribed about radius r has its corners r (1 / cos(pi / n) - 1)
    // outside the circle.
    const double r = diameter / 2;
    const double needed = std::numbers::pi / std::acos(1.0 / (1.0 + tolerance / r));
    const int n = std::max(32, static_cast<int>(std::ceil(needed)));
    return (n + 3) / 4 * 4;
}

}  // namespace rfd::holders
