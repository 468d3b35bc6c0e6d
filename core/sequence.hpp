#pragma once
// Low-discrepancy points in the unit square: Roberts' R2 sequence (the generalised golden
// ratio in two dimensions). Any run of consecutive points covers the square evenly, so a
// sampler can hand out runs of it (a few points per light direction, say) and all of them
// together still fill the square. Deterministic.
//
// Example: Eigen::Vector2d u = r2_point(17);  // in [0, 1)^2

#include <cmath>
#include <cstddef>

#include <Eigen/Core>

namespace rfd {

inline Eigen::Vector2d r2_point(std::size_t index) {
    constexpr double g = 1.32471795724474602596;  // the plastic number: g^3 = g + 1
    const double i = static_cast<double>(index);
    return {std::fmod(0.5 + i / g, 1.0), std::fmod(0.5 + i / (g * g), 1.0)};
}

}  // namespace rfd
