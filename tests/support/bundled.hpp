#pragma once
// The bundled designs (designs/design1.toml ... design4.toml) as the tests load them.

#include <filesystem>
#include <string>

#include "optics/design.hpp"

namespace rfd::testing {

inline const std::filesystem::path kBundledDesigns = std::filesystem::path(RFD_SOURCE_DIR) / "designs";

/// designs/designN.toml
inline std::string bundled_design_path(int n) {
    return (kBundledDesigns / ("design" + std::to_string(n) + ".toml")).string();
}

inline optics::Design bundled_design(int n) { return optics::load_design(bundled_design_path(n)); }

}  // namespace rfd::testing
