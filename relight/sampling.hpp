#pragma once
// Near-uniform light directions on the upper hemisphere by electrostatic repulsion (thesis
// 5.2): charges start at seed-dependent positions and move along their tangential Coulomb
// forces until the pattern settles into a roughly hexagonal lattice.
//
// The hemisphere is made a closed surface by mirroring: every charge at (x, y, z) has an
// image charge at (x, y, -z). The pattern is then the upper half of a mirror-symmetric
// distribution of 2n charges over the whole sphere, so charges spread evenly down to about
// half a spacing above the horizon instead of piling up along it (a hemisphere with a hard
// wall at z = 0 collects charges on the wall), and the count on the hemisphere is exactly n.
//
// Frame: the field frame of core/sphere.hpp (upper hemisphere z > 0).
//
// Example: std::vector<Eigen::Vector3d> lights = repulsion_pattern(256, /*seed=*/1);

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace rfd::relight {

struct RepulsionOptions {
    std::size_t max_iterations = 80;   ///< each costs one or two O(n^2) passes
    /// Stop once no charge moves farther than this fraction of the ideal spacing.
    double tolerance = 1e-3;
};

/// `count` unit directions with z > 0, deterministic for (count, seed).
std::vector<Eigen::Vector3d> repulsion_pattern(std::size_t count, std::uint64_t seed);
std::vector<Eigen::Vector3d> repulsion_pattern(std::size_t count, std::uint64_t seed,
                                               const RepulsionOptions& options);

/// Coulomb energy sum 1/|p_i - q| over the charges and their mirror images (each pair once;
/// a charge and its own image count as a pair). Lower is more uniform.
double repulsion_energy(const std::vector<Eigen::Vector3d>& directions);

/// The side of a hexagonal lattice with `count` points over the hemisphere's 2 pi sr,
/// radians (small-angle): the nearest-neighbour angle an ideal pattern would have.
double ideal_spacing(std::size_t count);

/// Nearest-neighbour angle of every direction, radians (infinity for a single direction).
std::vector<double> nearest_neighbour_angles(const std::vector<Eigen::Vector3d>& directions);

}  // namespace rfd::relight
