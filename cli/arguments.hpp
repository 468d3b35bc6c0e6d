#pragma once
// Command-line values several commands share, parsed with messages that name the option.

#include <string>
#include <utility>

#include "relight/interpolation.hpp"
#include "relight/scene.hpp"

namespace rfd::cli {

/// "WIDTHxHEIGHT" (each within [1, 16384]); InputError naming --resolution otherwise.
std::pair<int, int> parse_resolution(const std::string& text);

/// --resolution and --samples-per-pixel on a loaded scene: an empty resolution or a
/// non-positive sample count leaves the scene's own value.
void apply_scene_overrides(relight::Scene& scene, const std::string& resolution, int samples_per_pixel);

/// --interpolation: "delaunay", "solid-angle" or "nearest"; InputError naming it otherwise.
relight::Interpolation parse_interpolation(const std::string& text);

}  // namespace rfd::cli
