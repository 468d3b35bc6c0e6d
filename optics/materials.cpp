#include "optics/materials.hpp"

namespace rfd::optics {

const std::vector<Material>& material_catalogue() {
    static const std::vector<Material> catalogue = {
        {"air", 1.0, "by definition (vacuum is 1.000; air 1.0003 is within this model)"},
        {"N-BK7", 1.5168, "Schott datasheet, n_d"},
        {"B270", 1.5230, "Schott B 270 datasheet, n_d (moulded lenslet arrays)"},
        {"fused-silica", 1.4585, "Corning 7980 / Heraeus datasheet, n_d"},
        {"PMMA", 1.4917, "acrylic, typical n_d (Fresnel Technologies lens arrays)"},
        {"polycarbonate", 1.5855, "typical n_d"},
        {"PET", 1.65, "polyester film, typical in-plane n_d (transparencies)"},
    };
    return catalogue;
}

std::optional<double> material_index(std::string_view name) {
    for (const auto& m : material_catalogue())
        if (m.name == name) return m.index_d;
    return std::nullopt;
}

std::string material_names() {
    std::string names;
    for (const auto& m : material_catalogue())
        names += (names.empty() ? "" : ", ") + std::string(m.name);
    return names;
}

}  // namespace rfd::optics
