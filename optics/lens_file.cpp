#include "optics/lens_file.hpp"

#include <cmath>

#include "optics/materials.hpp"

namespace rfd::optics {
namespace {

SequentialSystem build(ConfigTable& root) {
    SequentialSystem system;
    system.name = root.optional_string("name").value_or(root.file());
    root.optional_string("source");  // free text: where the prescription comes from
    system.index_before = root.optional_number("index_before", 1.0, 4.0).value_or(1.0);
    auto tables = root.table_array("surface");
    if (tables.size() < 2) root.fail("surface", "a lens system needs at least two surfaces");
    double z = 0.0;
    for (std::size_t s = 0; s < tables.size(); ++s) {
        ConfigTable& t = tables[s];
        Surface surface;
        surface.z = z;
        surface.label = t.optional_string("label").value_or("S" + std::to_string(s + 1));
        if (t.has("radius")) {
            if (t.string("radius") != "flat")
                t.fail("radius", "expected radius = \"flat\" or a number in radius_mm");
            surface.profile = Flat{};
            if (t.has("radius_mm")) t.fail("radius_mm", "give either radius_mm or radius = \"flat\"");
        } else {
            const double radius = t.number("radius_mm", -1e9, 1e9);
            if (radius == 0.0) t.fail("radius_mm", "a radius of 0 is not a surface; use radius = \"flat\"");
            surface.profile = Conic{1.0 / radius, t.optional_number("conic", -1e6, 1e6).value_or(0.0)};
        }
        if (!std::holds_alternative<Conic>(surface.profile) && t.has("conic"))
            t.fail("conic", "a flat surface has no conic constant");
        surface.index_after = read_medium(t);
        const double semi = t.positive("semi_diameter_mm");
        surface.aperture = CircularAperture{semi};
        // The conic must reach the rim.
        if (!sag(surface.profile, semi * semi))
            t.fail("semi_diameter_mm", "the surface does not extend to this semi-diameter "
                                       "(|radius| too small for the aperture)");
        const bool last = s + 1 == tables.size();
        const auto thickness = last ? t.optional_number("thickness_mm", 0.0, 1e6)
                                    : std::optional<double>(t.non_negative("thickness_mm"));
        t.finish();
        system.surfaces.push_back(surface);
        if (thickness) z += *thickness;
        if (last && thickness)
            system.surfaces.push_back(Surface{Flat{}, Unbounded{}, z, surface.index_after, std::string(kImagePlaneLabel)});
    }
    // Neighbouring surfaces must not cut through each other inside their apertures.
    for (std::size_t s = 1; s < system.surfaces.size(); ++s) {
        const Surface& a = system.surfaces[s - 1];
        const Surface& b = system.surfaces[s];
        const auto* ca = std::get_if<CircularAperture>(&a.aperture);
        const auto* cb = std::get_if<CircularAperture>(&b.aperture);
        if (!ca || !cb) continue;
        // Sampled across the aperture, not only at the rim: two conics can cross inside it
        // and part again before the rim (a strong asphere close to a sphere).
        const double semi = std::min(ca->semi_diameter, cb->semi_diameter);
        double gap = HUGE_VAL, at = 0.0;
        constexpr int kSamples = 256;
        for (int k = 1; k <= kSamples; ++k) {
            const double r = semi * k / kSamples;
            const double g = (b.z + sag(b.profile, r * r).value_or(0.0)) -
                             (a.z + sag(a.profile, r * r).value_or(0.0));
            if (g < gap) {
                gap = g;
                at = r;
            }
        }
        if (gap < -1e-9)
            tables[std::min(s - 1, tables.size() - 1)].fail(
                "thickness_mm", "surfaces " + a.label + " and " + b.label +
                                    " intersect inside the aperture (gap " +
                                    std::to_string(gap) + " mm at radius " +
                                    std::to_string(at) + " mm)");
    }
    root.finish();
    system.validate();
    return system;
}

}  // namespace

double read_medium(ConfigTable& table) {
    const bool has_material = table.has("material");
    const bool has_index = table.has("index");
    if (has_material == has_index) {
        table.optional_string("material");
        table.fail(has_material ? "index" : "material",
                   "give exactly one of material = \"NAME\" or index = N for the medium behind");
    }
    if (has_index) return table.number("index", 1.0, 4.0);
    const std::string name = table.string("material");
    const auto index = material_index(name);
    if (!index) table.fail("material", "unknown material '" + name + "'; known: " + material_names());
    return *index;
}

SequentialSystem load_lens_system(const std::filesystem::path& path) {
    auto root = ConfigTable::parse_file(path);
    return build(root);
}

SequentialSystem parse_lens_system(std::string_view toml_text, const std::string& name) {
    auto root = ConfigTable::parse_string(toml_text, name);
    return build(root);
}

std::size_t last_lens_surface(const SequentialSystem& system) {
    RFD_CHECK(!system.surfaces.empty());
    const std::size_t last = system.surfaces.size() - 1;
    return last > 0 && system.surfaces[last].label == kImagePlaneLabel ? last - 1 : last;
}

}  // namespace rfd::optics
