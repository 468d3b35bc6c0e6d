#include "predict/optimize.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include <Eigen/Geometry>

#include "core/error.hpp"
#include "core/parallel.hpp"

namespace rfd::predict {
namespace {

double dot(std::span<const double> a, std::span<const double> b) {
    return std::inner_product(a.begin(), a.end(), b.begin(), 0.0);
}

}  // namespace

OptimizationProblem::OptimizationProblem(const DisplayOperator& op, std::vector<double> target,
                                         std::vector<double> weights, std::optional<LensletWindow> fitted,
                                         double core_weight)
    : op_(op), target_(std::move(target)), weights_(std::move(weights)), core_weight_(core_weight) {
    RFD_CHECK(core_weight >= 0.0);
    RFD_CHECK(target_.size() == op.output_size() && weights_.size() == op.directions());
    const optics::Lattice& lattice = op.nodes().lattice();
    fitted_.assign(op.nodes().lenslets(), 1);
    if (fitted)
        for (int j = 0; j < lattice.count_y(); ++j)
            for (int i = 0; i < lattice.count_x(); ++i) fitted_[lattice.linear_index({i, j})] = fitted->contains({i, j});
    for (double t : target_)
        if (!std::isfinite(t)) throw InputError("the optimiser's target holds a value that is not a number");
}

double OptimizationProblem::weight_of(std::size_t k) const {
    const std::size_t block = op_.block_size();
    const std::size_t within = (k % block) / 3;
    if (!fitted_[within % fitted_.size()]) return 0.0;
    return within < fitted_.size() ? weights_[k / block] : core_weight_ * weights_[k / block];
}

double OptimizationProblem::residual(std::span<const double> au, std::span<double> r) const {
    RFD_CHECK(au.size() == target_.size() && r.size() == target_.size());
    double f = 0.0;
    for (std::size_t k = 0; k < au.size(); ++k) {
        const double w = weight_of(k), e = au[k] - target_[k];
        r[k] = w * e;
        f += w * e * e;
    }
    return 0.5 * f;
}

namespace {

// Projected gradient, Barzilai-Borwein steps, exact line search on the segment to the
// projected point (the box is convex, so the whole segment is feasible).
OptimizationResult solve_bounded(const OptimizationProblem& problem, std::vector<double> x, const SolverOptions& options) {
    const DisplayOperator& op = problem.op();
    for (double& v : x) v = std::clamp(v, 0.0, 1.0);
    std::vector<double> ax(op.output_size()), r(op.output_size()), g(op.input_size());
    op.forward(x, ax);
    double f = problem.residual(ax, r);
    op.adjoint(r, g);
    OptimizationResult result;
    result.objective.push_back(f);
    std::vector<double> step(x.size()), a_step(ax.size()), g_new(g.size()), ax_new(ax.size());
    double alpha = 0.0;
    {
        double largest = 0.0;
        for (std::size_t k = 0; k < x.size(); ++k)
            largest = std::max(largest, std::abs(std::clamp(x[k] - g[k], 0.0, 1.0) - x[k]));
        alpha = largest > 0.0 ? 1.0 / largest : 1.0;
    }
    for (int it = 1; it <= options.iterations; ++it) {
        double largest = 0.0;
        for (std::size_t k = 0; k < x.size(); ++k) {
            step[k] = std::clamp(x[k] - alpha * g[k], 0.0, 1.0) - x[k];
            largest = std::max(largest, std::abs(step[k]));
        }
        const double slope = dot(g, step);
        if (largest == 0.0 || !(slope < 0.0)) {
            result.converged = true;
            break;
        }
        op.forward(step, a_step);
        double curvature = 0.0;
        for (std::size_t k = 0; k < a_step.size(); ++k) curvature += problem.weight_of(k) * a_step[k] * a_step[k];
        const double lambda = curvature > 0.0 ? std::min(1.0, -slope / curvature) : 1.0;
        for (std::size_t k = 0; k < ax.size(); ++k) ax_new[k] = ax[k] + lambda * a_step[k];
        const double f_new = problem.residual(ax_new, r);
        if (!(f_new <= f)) {  // rounding at the optimum: keep the better point
            result.converged = true;
            break;
        }
        op.adjoint(r, g_new);
        double ss = 0.0, sy = 0.0;
        for (std::size_t k = 0; k < x.size(); ++k) {
            const double s = lambda * step[k];
            x[k] += s;
            ss += s * s;
            sy += s * (g_new[k] - g[k]);
        }
        alpha = sy > 0.0 ? std::clamp(ss / sy, 1e-12, 1e12) : 1e12;
        std::swap(g, g_new);
        std::swap(ax, ax_new);
        const double decrease = f - f_new;
        f = f_new;
        result.objective.push_back(f);
        result.iterations = it;
        if (options.on_iteration) options.on_iteration(it, f, x);
        if (decrease <= options.tolerance * f) {
            result.converged = true;
            break;
        }
    }
    result.u = std::move(x);
    return result;
}

// CGLS on the weighted problem: min |M (A x - b)|, M = diag(sqrt(w)).
OptimizationResult solve_unbounded(const OptimizationProblem& problem, std::vector<double> x,
                                   const SolverOptions& options) {
    const DisplayOperator& op = problem.op();
    const std::size_t m = op.output_size();
    std::vector<double> sqrt_w(m);
    for (std::size_t k = 0; k < m; ++k) sqrt_w[k] = std::sqrt(problem.weight_of(k));
    std::vector<double> ax(m), r(m), mr(m), s(x.size()), p, q(m);
    op.forward(x, ax);
    for (std::size_t k = 0; k < m; ++k) r[k] = sqrt_w[k] * (problem.target()[k] - ax[k]);
    auto objective = [&] { return 0.5 * dot(r, r); };
    for (std::size_t k = 0; k < m; ++k) mr[k] = sqrt_w[k] * r[k];
    op.adjoint(mr, s);
    p = s;
    double gamma = dot(s, s);
    OptimizationResult result;
    result.objective.push_back(objective());
    for (int it = 1; it <= options.iterations && gamma > 0.0; ++it) {
        op.forward(p, q);
        for (std::size_t k = 0; k < m; ++k) q[k] *= sqrt_w[k];
        const double qq = dot(q, q);
        if (!(qq > 0.0)) break;
        const double alpha = gamma / qq;
        for (std::size_t k = 0; k < x.size(); ++k) x[k] += alpha * p[k];
        for (std::size_t k = 0; k < m; ++k) r[k] -= alpha * q[k];
        for (std::size_t k = 0; k < m; ++k) mr[k] = sqrt_w[k] * r[k];
        op.adjoint(mr, s);
        const double gamma_new = dot(s, s);
        for (std::size_t k = 0; k < x.size(); ++k) p[k] = s[k] + gamma_new / gamma * p[k];
        gamma = gamma_new;
        const double f_old = result.objective.back(), f = objective();
        result.objective.push_back(f);
        result.iterations = it;
        if (options.on_iteration) options.on_iteration(it, f, x);
        if (f_old - f <= options.tolerance * f) {
            result.converged = true;
            break;
        }
    }
    result.u = std::move(x);
    return result;
}

}  // namespace

OptimizationResult solve(const OptimizationProblem& problem, std::vector<double> start, const SolverOptions& options) {
    RFD_CHECK(start.size() == problem.op().input_size() && options.iterations >= 0);
    return options.bounded ? solve_bounded(problem, std::move(start), options)
                           : solve_unbounded(problem, std::move(start), options);
}

}  // namespace rfd::predict
