#pragma once
// Refractive indices of the glasses and plastics the presets use, at the helium d line
// (587.6 nm), from the makers' datasheets (Schott for N-BK7 and B270, typical values for
// the plastics). Dispersion is not modelled: the display works with white light and the
// thesis designs with one index per part.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rfd::optics {

struct Material {
    std::string_view name;
    double index_d;             ///< n at 587.6 nm
    std::string_view source;    ///< where the number comes from
};

/// The built-in catalogue.
const std::vector<Material>& material_catalogue();
/// Index of a catalogue material by name (case-sensitive), nullopt if unknown.
std::optional<double> material_index(std::string_view name);
/// Names of all catalogue materials, comma-separated, for error messages.
std::string material_names();

}  // namespace rfd::optics
