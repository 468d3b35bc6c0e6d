#pragma once
// Numbers and directions as rfd writes them into messages, reports and file attributes:
// one formatter for each, so the same value reads the same everywhere.
//
// Example: format_number(0.1 + 0.2)            // "0.3"
//          format_number(1.0 / 3.0, 9)         // "0.333333333"
//          format_fixed(0.25, 3)               // "0.250"
//          format_direction(Eigen::Vector3d::UnitZ())  // "theta 0.00 deg, phi 0.00 deg"
//          report += format_text("  time %.2f s\n", seconds);

#include <string>

#include <Eigen/Core>

namespace rfd {

/// `value` with at most `significant` significant digits, trailing zeros dropped, as
/// printf's %g writes it ("2880", "0.25", "1e-05", "inf", "nan").
std::string format_number(double value, int significant = 6);

/// `value` with exactly `decimals` digits after the point, as printf's %.Nf writes it
/// ("0.250", "12").
std::string format_fixed(double value, int decimals);

/// printf into a string, whatever its length: the lines of the reports commands print.
[[gnu::format(printf, 1, 2)]] std::string format_text(const char* format, ...);

/// A unit direction (core/sphere.hpp's frame) as its polar and azimuth angles in degrees,
/// two decimals: "theta 41.57 deg, phi -142.59 deg".
std::string format_direction(const Eigen::Vector3d& direction);

}  // namespace rfd
