#include "core/text.hpp"

#include <algorithm>
#include <cstdarg>
#include <cstdio>

#include "core/sphere.hpp"
#include "core/units.hpp"

namespace rfd {

std::string format_number(double value, int significant) {
    char text[64];
    std::snprintf(text, sizeof text, "%.*g", std::clamp(significant, 1, 17), value);
    return text;
}

std::string format_text(const char* format, ...) {
    std::va_list args;
    va_start(args, format);
    std::va_list again;
    va_copy(again, args);
    const int length = std::vsnprintf(nullptr, 0, format, args);
    va_end(args);
    std::string text(static_cast<std::size_t>(std::max(length, 0)), '\0');
    std::vsnprintf(text.data(), text.size() + 1, format, again);
    va_end(again);
    return text;
}

std::string format_fixed(double value, int decimals) {
    char text[352];  // %.17f of the largest double
    std::snprintf(text, sizeof text, "%.*f", std::clamp(decimals, 0, 17), value);
    return text;
}

std::string format_direction(const Eigen::Vector3d& direction) {
    const SphericalAngles a = angles_of(direction);
    char text[96];
    std::snprintf(text, sizeof text, "theta %.2f deg, phi %.2f deg", radians_to_degrees(a.theta),
                  radians_to_degrees(a.phi));
    return text;
}

}  // namespace rfd
