#pragma once
// Patterns optimised through the display's own forward model (Designs I and II).
//
// The direct encoder (patterns/encode.hpp) writes every dot as if the light through a
// lenslet reached only that lenslet's cell on the diffuser. It does not: a Design I's
// spot slides over the neighbours' cells as the light moves, a Design II's macro-pixel is
// imaged at |m| > 1 and overlaps them. Here the pattern is chosen so that what the
// simulator predicts comes closest to the field relit in software.
//
// The unknowns are nodes on the pattern plane (predict/node_grid.hpp), the display a linear
// map from them to the picture (predict/display_operator.hpp); this file is the problem
// and its solvers.
//
// Problem. minimise f(u) = 1/2 sum_d w_d |A_d u - W_d u*_d|^2 over 0 <= u <= 1, w_d the
// solid angle a direction stands for (normalised to mean 1). Solved by projected gradient
// with Barzilai-Borwein steps and an exact line search along the projected direction (the
// objective is quadratic, so the step is closed-form and f never increases; Dai and
// Fletcher 2005), or without the bounds by CGLS (Hestenes-Stiefel conjugate gradients on
// the normal equations) for the unconstrained optimum, the ceiling.
//
// Example:
//   NodeGrid nodes(lattice, geometry, 0.1);
//   DisplayOperator A(simulator, nodes, directions, options);
//   OptimizationProblem problem(A, targets, weights);
//   OptimizationResult r = solve(problem, direct_nodes(nodes, encoder, tone), {});

#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "core/options.hpp"
#include "optics/display.hpp"
#include "predict/display_operator.hpp"
#include "predict/node_grid.hpp"

namespace rfd::predict {

/// f(u) of the header: the operator, the targets W_d u*_d (output_size()) and per-direction
/// weights; cells outside `fitted` (default: all) do not count.
class OptimizationProblem {
public:
    /// `core_weight`: the cores' share beside the whole cells' (when op has cores).
    OptimizationProblem(const DisplayOperator& op, std::vector<double> target, std::vector<double> weights,
                        std::optional<LensletWindow> fitted = std::nullopt, double core_weight = 1.0);
    const DisplayOperator& op() const { return op_; }
    const std::vector<double>& target() const { return target_; }
    /// r = w (A u - target) per output value (w: the direction's weight, 0 outside the
    /// fitted cells), so that A^T r is the gradient; returns f.
    double residual(std::span<const double> au, std::span<double> r) const;
    /// The weight of output value k (0 outside the fitted window).
    double weight_of(std::size_t k) const;

private:
    const DisplayOperator& op_;
    std::vector<double> target_, weights_;
    std::vector<std::uint8_t> fitted_;  // per lenslet
    double core_weight_ = 0.0;
};

/// `rfd pattern optimize`'s and a project's [optimize] settings.
inline constexpr IntegerOption kIterationsOption{"--iterations", "iterations", "", 0, 100000, 40,
                                                 "At most this many solver iterations"};
inline constexpr NumberOption kStopFractionOption{"--stop-fraction", "", "", 0.0, 1.0, 1e-5,
                                                  "Stop when an iteration lowers the objective by less than this "
                                                  "fraction of it",
                                                  "--tolerance"};
inline constexpr NumberOption kNodeSpacingOption{"--spacing", "spacing_mm", "mm", 0.005, 2.0, 0.1,
                                                 "Node spacing on the pattern plane: the pattern's unknowns, per "
                                                 "lenslet"};
inline constexpr NumberOption kCoreWeightOption{"--core-weight", "core_weight", "", 0.0, 1e6, 0.0,
                                                "Design II: also fit the macro-pixels' cores, where no neighbour "
                                                "reaches, this much beside the whole cells (0: whole cells, the "
                                                "picture at the display's resolution)"};
/// The optimiser's rays: kRaysPerSideOption's default, fewer at most (a full grid per
/// direction and lenslet is held in memory).
inline constexpr IntegerOption kOptimizeRaysOption{"--rays-per-side", "", "", 1, 64, optics::kRaysPerSideOption.fallback,
                                                   optics::kRaysPerSideOption.help, "--rays"};

struct SolverOptions {
    int iterations = static_cast<int>(kIterationsOption.fallback);
    /// Stop when an iteration lowers f by less than this fraction of f.
    double tolerance = kStopFractionOption.fallback;
    bool bounded = true;  ///< 0 <= u <= 1; false: CGLS, unconstrained
    /// Called after every iteration with its number, f, and the iterate (for charts).
    std::function<void(int, double, std::span<const double>)> on_iteration;
};

struct OptimizationResult {
    std::vector<double> u;
    std::vector<double> objective;  ///< f at the start and after each iteration
    int iterations = 0;
    bool converged = false;         ///< the tolerance was met (or the projected gradient vanished)
};

/// Minimises the problem's f from `start` (clamped to the bounds when bounded).
OptimizationResult solve(const OptimizationProblem& problem, std::vector<double> start, const SolverOptions& options);

}  // namespace rfd::predict
