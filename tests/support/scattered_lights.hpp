#pragma once
// Light directions scattered at random over the hemisphere down to 75 degrees from the
// zenith (uniform in area), from a seed: irregular lights for fits and leave-one-out.

#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "core/sphere.hpp"
#include "core/units.hpp"

namespace rfd::testing {

inline std::vector<Eigen::Vector3d> scattered_lights(std::size_t count, unsigned seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<Eigen::Vector3d> out;
    for (std::size_t i = 0; i < count; ++i)
        out.push_back(direction_from_angles(degrees_to_radians(75.0) * std::sqrt(unit(random)), 2.0 * kPi * unit(random)));
    return out;
}

}  // namespace rfd::testing
