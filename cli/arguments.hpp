#pragma once
// Command-line values several commands share, parsed with messages that name the option.

#include <string>
#include <utility>

#include "relight/scene.hpp"

namespace rfd::cli {

/// "WIDTHxHEIGHT" (each within [1, 16384]); InputError naming --resolution otherwise.
std::pair<int, int> parse_resolution(const std::string& text);

/// --resolution and --samples-per-pixel on a loaded scene: an empty resolution or a
/// non-positive sample count leaves the scene's own value.
void apply_scene_overrides(relight::Scene& scene, const std::string& resolution, int samples_per_pixel);

}  // namespace rfd::cli
