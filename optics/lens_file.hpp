#pragma once
// The lens-system file: a TOML list of sequential surfaces, for checking single catalogue
// lenses and stacks on their own (docs/formats.md has the full reference).
//
//   name = "Edmund Optics 25 mm x 50 mm PCX, N-BK7"
//   [[surface]]
//   radius_mm = 25.84          # or: radius = "flat"
//   conic = 0.0                # optional, default 0 (sphere)
//   thickness_mm = 5.3         # vertex distance to the next surface
//   material = "N-BK7"         # medium behind this surface: material or index
//   semi_diameter_mm = 12.5
//   [[surface]]
//   radius = "flat"
//   material = "air"
//   semi_diameter_mm = 12.5
//
// The first vertex sits at z = 0. The last surface's thickness_mm is optional; when given,
// an unbounded flat "image" plane is added at that distance.

#include <cstddef>
#include <filesystem>
#include <string_view>

#include "core/config.hpp"
#include "optics/system.hpp"

namespace rfd::optics {

/// Label of the image plane a lens file's last thickness adds.
inline constexpr std::string_view kImagePlaneLabel = "image";

SequentialSystem load_lens_system(const std::filesystem::path& path);
SequentialSystem parse_lens_system(std::string_view toml_text, const std::string& name);

/// Index of the lens's last surface: the image plane, if there is one, is where the light
/// is looked at, not a surface of the lens (back focal length is measured from this one).
std::size_t last_lens_surface(const SequentialSystem& system);

/// Reads the medium of a table: exactly one of `material = "N-BK7"` or `index = 1.5168`.
double read_medium(ConfigTable& table);

}  // namespace rfd::optics
