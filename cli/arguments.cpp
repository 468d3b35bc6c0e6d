#include "cli/arguments.hpp"

#include <cstdio>

#include "core/error.hpp"

namespace rfd::cli {

std::pair<int, int> parse_resolution(const std::string& text) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') ||
        w < 1 || h < 1 || w > 16384 || h > 16384)
        throw InputError("--resolution: expected WIDTHxHEIGHT such as 256x128, got '" + text + "'");
    return {w, h};
}

void apply_scene_overrides(relight::Scene& scene, const std::string& resolution, int samples_per_pixel) {
    if (!resolution.empty()) {
        const auto [w, h] = parse_resolution(resolution);
        for (auto& camera : scene.cameras) {
            camera.width = w;
            camera.height = h;
        }
    }
    if (samples_per_pixel > 0) scene.samples_per_pixel = samples_per_pixel;
}

relight::Interpolation parse_interpolation(const std::string& text) {
    if (text == "delaunay") return relight::Interpolation::delaunay;
    if (text == "solid-angle") return relight::Interpolation::solid_angle;
    if (text == "nearest") return relight::Interpolation::nearest;
    throw InputError("--interpolation: expected 'delaunay', 'solid-angle' or 'nearest', got '" + text + "'");
}

}  // namespace rfd::cli
