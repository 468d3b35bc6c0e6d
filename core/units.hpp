#pragma once
// Units used across rfd. Lengths are millimetres, angles in files and on the command line
// are degrees, angles inside numerical code are radians, print resolution is dots per inch.
// Dpi is a strong type: a resolution passed where a length or an angle is expected (or
// the other way round) does not compile.

#include <numbers>

namespace rfd {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kMillimetresPerInch = 25.4;

constexpr double degrees_to_radians(double degrees) { return degrees * kPi / 180.0; }
constexpr double radians_to_degrees(double radians) { return radians * 180.0 / kPi; }

/// A print resolution in dots per inch along one axis.
struct Dpi {
    double value = 0.0;
    constexpr explicit Dpi(double v = 0.0) : value(v) {}
    /// Size of one printer dot in millimetres.
    constexpr double dot_mm() const { return kMillimetresPerInch / value; }
};

}  // namespace rfd
