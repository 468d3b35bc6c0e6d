#include "patterns/procedural.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "patterns/glyphs.hpp"

namespace rfd::patterns {
namespace {

// Colours of successive letters: saturated, distinct, none black.
constexpr std::array<std::array<float, 3>, 6> kPalette = {{{1.0f, 0.2f, 0.2f},
                                                           {0.2f, 1.0f, 0.2f},
                                                           {0.3f, 0.4f, 1.0f},
                                                           {1.0f, 0.9f, 0.1f},
                                                           {1.0f, 0.3f, 1.0f},
                                                           {0.1f, 1.0f, 1.0f}}};

Image coloured(const Image& mask, const std::array<float, 3>& colour) {
    Image image(mask.width(), mask.height(), 3);
    for (int c = 0; c < 3; ++c)
        for (int y = 0; y < mask.height(); ++y)
            for (int x = 0; x < mask.width(); ++x)
                image.at(x, y, c) = mask.at(x, y, 0) * colour[static_cast<std::size_t>(c)];
    return image;
}

// A diamond |u| + |v| <= size, hollow inside |u| + |v| < hole (u, v in [-1, 1] over the image).
Image diamond(int width, int height, double size, double hole) {
    Image image(width, height, 3);
    constexpr int kSub = 4;  // antialiasing: 4 x 4 samples per pixel
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            int inside = 0;
            for (int sy = 0; sy < kSub; ++sy)
                for (int sx = 0; sx < kSub; ++sx) {
                    const double u = 2.0 * (x + (sx + 0.5) / kSub) / width - 1.0;
                    const double v = 2.0 * (y + (sy + 0.5) / kSub) / height - 1.0;
                    const double r = std::abs(u) + std::abs(v);
                    inside += (r <= size && r >= hole) ? 1 : 0;
                }
            for (int c = 0; c < 3; ++c) image.at(x, y, c) = static_cast<float>(inside) / (kSub * kSub);
        }
    return image;
}

Image bars(int width, int height, bool horizontal) {
    Image image(width, height, 3);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const double u = (x + 0.5) / width, v = (y + 0.5) / height;
            const bool on = horizontal ? ((v > 0.2 && v < 0.4) || (v > 0.6 && v < 0.8)) && u > 0.1 && u < 0.9
                                       : (u > 0.4 && u < 0.6) && v > 0.1 && v < 0.9;
            for (int c = 0; c < 3; ++c) image.at(x, y, c) = on ? 1.0f : 0.0f;
        }
    return image;
}

}  // namespace

relight::ReflectanceField procedural_field(const ProceduralOptions& options) {
    if (options.width <= 0 || options.height <= 0)
        throw InputError("--resolution: the procedural field needs a positive size");
    if (!(options.spread_deg > 0.0 && options.spread_deg <= 80.0))
        throw InputError("--spread: expected an angle within (0, 80] degrees");
    const double spread = degrees_to_radians(options.spread_deg);
    relight::ReflectanceField field;
    double spacing = spread;  // angle between neighbouring picture directions
    switch (options.kind) {
        case ProceduralKind::Letters: {
            if (options.text.empty()) throw InputError("--text: the letters field needs at least one character");
            const std::size_t n = options.text.size();
            if (n > 1) spacing = 2.0 * spread / static_cast<double>(n - 1);
            for (std::size_t k = 0; k < n; ++k) {
                // Left to right: field x from -spread to +spread along the horizon's arc.
                const double theta = n == 1 ? 0.0 : -spread + spacing * static_cast<double>(k);
                field.directions.push_back(direction_from_angles(std::abs(theta), theta < 0 ? kPi : 0.0));
                const Image mask = text_mask(std::string(1, options.text[k]), options.width, options.height);
                field.images.push_back(coloured(mask, kPalette[k % kPalette.size()]));
            }
            break;
        }
        case ProceduralKind::Bars:
            field.directions.push_back(direction_from_angles(spread, kPi));  // from the left
            field.images.push_back(bars(options.width, options.height, true));
            field.directions.push_back(direction_from_angles(spread, 0.0));  // from the right
            field.images.push_back(bars(options.width, options.height, false));
            spacing = spread;
            break;
        case ProceduralKind::Diamonds: {
            const int steps = options.diamond_steps;
            if (steps < 2) throw InputError("--steps: the diamonds field needs at least 2 directions per side");
            spacing = 2.0 * spread / (steps - 1);
            for (int j = 0; j < steps; ++j)
                for (int i = 0; i < steps; ++i) {
                    const double sx = -1.0 + 2.0 * i / (steps - 1), sy = -1.0 + 2.0 * j / (steps - 1);
                    const Eigen::Vector3d d(std::sin(spread) * sx, std::sin(spread) * sy, 1.0);
                    field.directions.push_back(d.normalized());
                    // Light moving down (sy -> -1) grows the diamond; sideways hollows it.
                    const double size = 0.35 + 0.3 * (1.0 - sy);
                    const double hole = size * 0.8 * std::abs(sx);
                    field.images.push_back(diamond(options.width, options.height, size, hole));
                }
            break;
        }
    }
    // Guards: black, at least one spacing away from every picture direction.
    const double keep_out = std::max(spacing, degrees_to_radians(2.0));
    for (const Eigen::Vector3d& g : fibonacci_hemisphere(static_cast<std::size_t>(std::max(options.guards, 0)))) {
        bool far = true;
        for (std::size_t k = 0; k < field.images.size() && far; ++k) far = angle_between(g, field.directions[k]) >= keep_out;
        if (!far) continue;
        field.directions.push_back(g);
        field.images.emplace_back(options.width, options.height, 3, 0.0f);
    }
    return field;
}

}  // namespace rfd::patterns
