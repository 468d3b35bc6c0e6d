#include "relight/sampling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "core/parallel.hpp"
#include "core/sphere.hpp"

namespace rfd::relight {
namespace {

// Charge positions as separate coordinate arrays, so the all-pairs loops vectorise.
struct Charges {
    std::vector<double> x, y, z;
    std::size_t size() const { return x.size(); }
};

// Below this height a charge and its own image would nearly coincide; keeping charges just
// above the horizon keeps every distance finite.
constexpr double kMinimumHeight = 1e-9;

// Uniform doubles in [0, 1) from the engine's raw output: std::uniform_real_distribution is
// implementation-defined, and patterns must be the same from every standard library.
double unit_uniform(std::mt19937_64& engine) {
    return static_cast<double>(engine() >> 11) * 0x1.0p-53;
}

// Starting positions: a Fibonacci spiral over the hemisphere (equal area per point), turned
// by a random azimuth and jittered by a third of the spacing, so that different seeds give
// different patterns while relaxation starts close to equilibrium.
Charges initial_charges(std::size_t count, std::uint64_t seed) {
    std::mt19937_64 engine(seed);
    const double golden_angle = std::numbers::pi * (3.0 - std::sqrt(5.0));
    const double turn = 2.0 * std::numbers::pi * unit_uniform(engine);
    const double jitter = ideal_spacing(count) / 10.0;
    Charges charges;
    // The spiral ends half a spacing above the horizon: a charge right at it would nearly
    // touch its own image, and that one stiff force would throttle every step.
    const double lowest_z = std::sin(std::min(0.5 * ideal_spacing(count), 0.5));
    for (std::size_t i = 0; i < count; ++i) {
        const double z = 1.0 - (1.0 - lowest_z) * (static_cast<double>(i) + 0.5) /
                                   static_cast<double>(count);
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double phi = turn + golden_angle * static_cast<double>(i);
        Eigen::Vector3d p(r * std::cos(phi), r * std::sin(phi), z);
        p += jitter * Eigen::Vector3d(unit_uniform(engine) - 0.5, unit_uniform(engine) - 0.5,
                                      unit_uniform(engine) - 0.5);
        p.normalize();
        charges.x.push_back(p.x());
        charges.y.push_back(p.y());
        charges.z.push_back(std::max(std::abs(p.z()), kMinimumHeight));
    }
    return charges;
}

struct Field {
    double energy = 0.0;
    std::vector<Eigen::Vector3d> tangential_force;
};

// Energy (see repulsion_energy) and the tangential part of -grad E at every charge. Each
// charge's sums run over j in order, and the per-charge energies are added in order, so the
// result does not depend on how the loop is split between threads.
Field field_of(const Charges& c) {
    const std::size_t n = c.size();
    std::vector<double> energies(n);
    Field field;
    field.tangential_force.resize(n);
    parallel_for_chunks(n, 16, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            const double xi = c.x[i], yi = c.y[i], zi = c.z[i];
            double fx = 0.0, fy = 0.0, fz = 0.0, e = 0.0;
            for (std::size_t j = 0; j < n; ++j) {
                const double dx = xi - c.x[j], dy = yi - c.y[j];
                const double dz = zi - c.z[j], dz_image = zi + c.z[j];
                const double planar = dx * dx + dy * dy;
                // j == i: the zero distance becomes 1, its (zero) force stays zero and the
                // energy's spurious 1 is taken off below; a branch would stop vectorisation.
                const double r2 = planar + dz * dz + (j == i ? 1.0 : 0.0);
                const double r2_image = planar + dz_image * dz_image;
                const double inv = 1.0 / std::sqrt(r2);
                const double inv_image = 1.0 / std::sqrt(r2_image);
                const double inv3 = inv * inv * inv;
                const double inv3_image = inv_image * inv_image * inv_image;
                fx += dx * (inv3 + inv3_image);
                fy += dy * (inv3 + inv3_image);
                fz += dz * inv3 + dz_image * inv3_image;
                e += inv + inv_image;
            }
            energies[i] = 0.5 * (e - 1.0);
            const Eigen::Vector3d p(xi, yi, zi);
            const Eigen::Vector3d f(fx, fy, fz);
            field.tangential_force[i] = f - f.dot(p) * p;
        }
    });
    for (double e : energies) field.energy += e;
    return field;
}

Charges moved(const Charges& c, const std::vector<Eigen::Vector3d>& force, double step) {
    Charges next = c;
    for (std::size_t i = 0; i < c.size(); ++i) {
        Eigen::Vector3d p = Eigen::Vector3d(c.x[i], c.y[i], c.z[i]) + step * force[i];
        p.normalize();
        next.x[i] = p.x();
        next.y[i] = p.y();
        // A charge pushed through the horizon comes back as its own image.
        next.z[i] = std::max(std::abs(p.z()), kMinimumHeight);
    }
    return next;
}

double largest_norm(const std::vector<Eigen::Vector3d>& vectors) {
    double largest = 0.0;
    for (const auto& v : vectors) largest = std::max(largest, v.norm());
    return largest;
}

Charges charges_of(const std::vector<Eigen::Vector3d>& directions) {
    Charges c;
    for (const auto& d : directions) {
        const Eigen::Vector3d u = d.normalized();
        c.x.push_back(u.x());
        c.y.push_back(u.y());
        c.z.push_back(std::max(std::abs(u.z()), kMinimumHeight));
    }
    return c;
}

}  // namespace

double ideal_spacing(std::size_t count) {
    if (count == 0) return std::numeric_limits<double>::infinity();
    // Hexagonal cell area sqrt(3)/2 a^2 times count covers 2 pi.
    return std::sqrt(4.0 * std::numbers::pi / (std::sqrt(3.0) * static_cast<double>(count)));
}

std::vector<Eigen::Vector3d> repulsion_pattern(std::size_t count, std::uint64_t seed) {
    return repulsion_pattern(count, seed, RepulsionOptions{});
}

std::vector<Eigen::Vector3d> repulsion_pattern(std::size_t count, std::uint64_t seed,
                                               const RepulsionOptions& options) {
    if (count == 0) return {};
    Charges charges = initial_charges(count, seed);
    const double spacing = std::min(ideal_spacing(count), 1.0);
    Field field = field_of(charges);
    // Gradient descent with a step that grows while the energy falls and halves when it
    // does not; a step is measured by the farthest any charge moves.
    double largest_force = largest_norm(field.tangential_force);
    double step = largest_force > 0.0 ? 0.1 * spacing / largest_force : 0.0;
    for (std::size_t iteration = 0; iteration < options.max_iterations && step > 0.0; ++iteration) {
        if (step * largest_force < options.tolerance * spacing) break;
        Charges trial = moved(charges, field.tangential_force, step);
        Field trial_field = field_of(trial);
        if (trial_field.energy < field.energy) {
            charges = std::move(trial);
            field = std::move(trial_field);
            largest_force = largest_norm(field.tangential_force);
            step *= 1.2;
        } else {
            step *= 0.5;
        }
    }
    std::vector<Eigen::Vector3d> directions;
    directions.reserve(count);
    for (std::size_t i = 0; i < count; ++i) {
        // Unit to the last bit: normalising again (as light files and renderers do) must not
        // change a direction, or a pattern written out and read back renders differently.
        Eigen::Vector3d d(charges.x[i], charges.y[i], charges.z[i]);
        for (int pass = 0; pass < 4 && d.normalized() != d; ++pass) d.normalize();
        directions.push_back(d);
    }
    return directions;
}

double repulsion_energy(const std::vector<Eigen::Vector3d>& directions) {
    return field_of(charges_of(directions)).energy;
}

std::vector<double> nearest_neighbour_angles(const std::vector<Eigen::Vector3d>& directions) {
    const std::size_t n = directions.size();
    std::vector<double> nearest(n, std::numeric_limits<double>::infinity());
    parallel_for_chunks(n, 64, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            double largest_cosine = -2.0;
            std::size_t closest = i;
            for (std::size_t j = 0; j < n; ++j) {
                if (j == i) continue;
                const double c = directions[i].dot(directions[j]);
                if (c > largest_cosine) {
                    largest_cosine = c;
                    closest = j;
                }
            }
            if (closest != i) nearest[i] = angle_between(directions[i].normalized(), directions[closest].normalized());
        }
    });
    return nearest;
}

}  // namespace rfd::relight
