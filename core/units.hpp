#pragma once
// Units used across rfd. Lengths are millimetres, angles in files and on the command line
// are degrees, angles inside numerical code are radians, print resolution is dots per inch.
// The strong types below are for interfaces where swapping two doubles would go unnoticed.

#include <numbers>

namespace rfd {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kMillimetresPerInch = 25.4;

constexpr double degrees_to_radians(double degrees) { return degrees * kPi / 180.0; }
constexpr double radians_to_degrees(double radians) { return radians * 180.0 / kPi; }

/// A length in millimetres.
struct Millimetres {
    double value = 0.0;
    constexpr explicit Millimetres(double v = 0.0) : value(v) {}
};

/// An angle in degrees, as users write it.
struct Degrees {
    double value = 0.0;
    constexpr explicit Degrees(double v = 0.0) : value(v) {}
    constexpr double radians() const { return degrees_to_radians(value); }
};

/// A print resolution in dots per inch along one axis.
struct Dpi {
    double value = 0.0;
    constexpr explicit Dpi(double v = 0.0) : value(v) {}
    /// Size of one printer dot in millimetres.
    constexpr double dot_mm() const { return kMillimetresPerInch / value; }
};

}  // namespace rfd
