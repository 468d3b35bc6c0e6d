#include "predict/optimize.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include <Eigen/Geometry>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "predict/compare.hpp"

namespace rfd::predict {
namespace {

// Nodes per side of a lenslet's grid at most: a finer grid than this is finer than any
// printer resolves under a lenslet of a few millimetres.
constexpr int kMaxNodesPerSide = 256;

double dot(std::span<const double> a, std::span<const double> b) {
    return std::inner_product(a.begin(), a.end(), b.begin(), 0.0);
}

}  // namespace

NodeGrid::NodeGrid(const optics::Lattice& lattice, const patterns::PatternGeometry& geometry, double spacing_mm)
    : lattice_(lattice), geometry_(geometry), spacing_(spacing_mm) {
    if (!(spacing_mm > 0.0) || !std::isfinite(spacing_mm))
        throw InputError("the node spacing must be a positive number of millimetres, got " + std::to_string(spacing_mm));
    const double half_w = 0.5 * lattice.pitch_x();
    const double half_h =
        lattice.kind() == optics::LatticeKind::Hexagonal ? lattice.circumradius() : 0.5 * lattice.pitch_y();
    // An even count per side: the outer nodes lie within half a spacing of the cell's
    // bounding box, and the axis between the middle two.
    const double per_side = 2.0 * std::ceil(std::max(half_w, half_h) / spacing_mm);
    if (per_side > kMaxNodesPerSide)
        throw InputError("a node spacing of " + std::to_string(spacing_mm) + " mm gives more than " +
                         std::to_string(kMaxNodesPerSide) + " nodes per side of a lenslet: use a larger one");
    nodes_x_ = 2 * static_cast<int>(std::ceil(half_w / spacing_mm));
    nodes_y_ = 2 * static_cast<int>(std::ceil(half_h / spacing_mm));
}

bool NodeGrid::stencil(const Eigen::Vector2d& point, Stencil& out) const {
    const double fx = point.x() / geometry_.dot_x + 0.5 * geometry_.width;
    const double fy = 0.5 * geometry_.height - point.y() / geometry_.dot_y;
    if (!(fx >= 0.0 && fy >= 0.0 && fx < geometry_.width && fy < geometry_.height)) return false;
    return dot_stencil(static_cast<int>(fx), static_cast<int>(fy), out);
}

void NodeGrid::local_stencil(const Eigen::Vector2d& offset, std::array<std::uint32_t, 4>& index,
                             std::array<double, 4>& weight) const {
    const double ga = std::clamp(offset.x() / spacing_ + 0.5 * (nodes_x_ - 1), 0.0, nodes_x_ - 1.0);
    const double gb = std::clamp(offset.y() / spacing_ + 0.5 * (nodes_y_ - 1), 0.0, nodes_y_ - 1.0);
    const int a = std::min(static_cast<int>(ga), nodes_x_ - 2), b = std::min(static_cast<int>(gb), nodes_y_ - 2);
    const double ta = ga - a, tb = gb - b;
    const auto base = static_cast<std::uint32_t>((b * nodes_x_ + a) * 3);
    const auto row = static_cast<std::uint32_t>(nodes_x_ * 3);
    index = {base, base + 3, base + row, base + row + 3};
    weight = {(1.0 - ta) * (1.0 - tb), ta * (1.0 - tb), (1.0 - ta) * tb, ta * tb};
}

bool NodeGrid::dot_stencil(int px, int py, Stencil& out) const {
    const Eigen::Vector2d centre = geometry_.dot_centre(px, py);
    out.cell = lattice_.cell_at(centre);
    if (!lattice_.contains(out.cell)) return false;
    std::array<std::uint32_t, 4> local{};
    local_stencil(centre - lattice_.center(out.cell), local, out.weight);
    const std::size_t base = lattice_.linear_index(out.cell) * per_lenslet() * 3;
    for (int n = 0; n < 4; ++n) out.index[n] = base + local[n];
    return true;
}

DisplayOperator::DisplayOperator(const optics::DisplaySimulator& simulator, const NodeGrid& nodes,
                                 std::vector<Eigen::Vector3d> display_directions,
                                 const optics::SimulationOptions& options, std::optional<LensletWindow> sources,
                                 bool cores)
    : nodes_(nodes),
      sources_(sources.value_or(LensletWindow::whole(nodes.lattice())).clipped(nodes.lattice())),
      core_fraction_(cores ? macro_pixel_core(simulator.optics()).fraction : 1.0) {
    const optics::Lattice& lattice = nodes_.lattice();
    RFD_CHECK(lattice.count_x() == simulator.optics().lattice().count_x() &&
              lattice.count_y() == simulator.optics().lattice().count_y());
    optics::SimulationOptions full = options;
    full.max_rays_per_lenslet =
        static_cast<std::size_t>(options.rays_per_side) * static_cast<std::size_t>(options.rays_per_side);
    // Index steps between cells, from a source cell in an even and in an odd row (the
    // lattice is the same seen from any cell of a row's parity).
    const std::array<optics::CellIndex, 2> origins{optics::CellIndex{0, 0}, optics::CellIndex{0, 1}};
    auto step_to = [&](const Eigen::Vector2d& offset) {
        CellStep step;
        for (int parity = 0; parity < 2; ++parity) {
            const optics::CellIndex to = lattice.cell_at(lattice.center(origins[parity]) + offset);
            step.di[parity] = static_cast<std::int16_t>(to.i - origins[parity].i);
            step.dj[parity] = static_cast<std::int16_t>(to.j - origins[parity].j);
        }
        return step;
    };
    const Eigen::Vector2d origin = lattice.center(origins[0]);
    directions_.resize(display_directions.size());
    parallel_for_chunks(display_directions.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t d = begin; d < end; ++d) {
            Direction& out = directions_[d];
            out.display = display_directions[d].normalized();
            const optics::RepeatedRays traced = simulator.trace_lenslet({optics::DisplayLight{out.display}}, full);
            for (const optics::LensletRay& ray : traced.rays) {
                Ray r;
                r.read = step_to(ray.on_pattern);
                r.landing = step_to(ray.on_diffuser);
                const Eigen::Vector2d read_centre = lattice.center(lattice.cell_at(origin + ray.on_pattern)) - origin;
                nodes_.local_stencil(ray.on_pattern - read_centre, r.node, r.weight);
                r.power = ray.reaching / lattice.cell_area();
                const Eigen::Vector2d landing_centre = lattice.center(lattice.cell_at(origin + ray.on_diffuser)) - origin;
                if (core_fraction_ < 1.0 &&
                    lattice.cell_contains(origins[0], origin + (ray.on_diffuser - landing_centre) / core_fraction_))
                    r.core_power = r.power / (core_fraction_ * core_fraction_);
                r.first_crossed = static_cast<std::uint32_t>(out.crossed.size());
                for (std::size_t k = 0; k < ray.neighbours; ++k)
                    out.crossed.push_back(step_to(traced.neighbour_offsets[ray.first_neighbour + k]));
                r.crossed = static_cast<std::uint32_t>(out.crossed.size()) - r.first_crossed;
                out.rays.push_back(r);
            }
        }
    });
    int reach = 0;
    for (const Direction& direction : directions_)
        for (const Ray& ray : direction.rays)
            for (int parity = 0; parity < 2; ++parity)
                reach = std::max({reach, std::abs(int{ray.read.dj[parity]}), std::abs(int{ray.landing.dj[parity]})});
    reach_rows_ = reach;
}

template <typename Visit>
void DisplayOperator::for_each_ray(const Direction& direction, optics::CellIndex source, Visit&& visit) const {
    const optics::Lattice& lattice = nodes_.lattice();
    const int parity = source.j & 1;
    auto cell_of = [&](const CellStep& step) {
        return optics::CellIndex{source.i + step.di[parity], source.j + step.dj[parity]};
    };
    const std::size_t per_lenslet = nodes_.per_lenslet() * 3;
    for (const Ray& ray : direction.rays) {
        bool exists = true;
        for (std::uint32_t k = 0; exists && k < ray.crossed; ++k)
            exists = lattice.contains(cell_of(direction.crossed[ray.first_crossed + k]));
        const optics::CellIndex landing = cell_of(ray.landing);
        if (!exists || !lattice.contains(landing)) continue;
        const optics::CellIndex read = cell_of(ray.read);
        const bool printed = lattice.contains(read);
        visit(ray, printed, printed ? lattice.linear_index(read) * per_lenslet : 0, lattice.linear_index(landing));
    }
}

void DisplayOperator::forward_direction(std::size_t d, std::span<const double> u, std::span<double> y,
                                        double outside) const {
    RFD_CHECK(u.size() == input_size() && y.size() == block_size());
    std::fill(y.begin(), y.end(), 0.0);
    const std::size_t cores = regions() > 1 ? nodes_.lenslets() * 3 : 0;  // where the cores' block starts
    for (int j = sources_.j0; j < sources_.j1; ++j)
        for (int i = sources_.i0; i < sources_.i1; ++i)
            for_each_ray(directions_[d], {i, j},
                         [&](const Ray& ray, bool printed, std::size_t base, std::size_t landing) {
                             double* out = y.data() + landing * 3;
                             double* core = y.data() + cores + landing * 3;
                             const double* v = u.data() + base;
                             for (std::size_t c = 0; c < 3; ++c) {
                                 const double value =
                                     printed ? ray.weight[0] * v[ray.node[0] + c] + ray.weight[1] * v[ray.node[1] + c] +
                                                   ray.weight[2] * v[ray.node[2] + c] + ray.weight[3] * v[ray.node[3] + c]
                                             : outside;
                                 out[c] += ray.power * value;
                                 if (ray.core_power != 0.0) core[c] += ray.core_power * value;
                             }
                         });
}

void DisplayOperator::forward(std::span<const double> u, std::span<double> y, double outside) const {
    RFD_CHECK(y.size() == output_size());
    const std::size_t block = block_size();
    parallel_for_chunks(directions_.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t d = begin; d < end; ++d) forward_direction(d, u, y.subspan(d * block, block), outside);
    });
}

void DisplayOperator::adjoint(std::span<const double> y, std::span<double> g) const {
    RFD_CHECK(y.size() == output_size() && g.size() == input_size());
    std::fill(g.begin(), g.end(), 0.0);
    const LensletWindow& window = sources_;
    if (window.i0 >= window.i1 || window.j0 >= window.j1) return;
    const std::size_t block = block_size();
    const std::size_t cores = regions() > 1 ? nodes_.lenslets() * 3 : 0;
    // A source lenslet writes nodes at most reach_rows() rows away: bands of 2 reach_rows()
    // rows, every other one at a time, never write the same node.
    const int band_rows = std::max(1, 2 * reach_rows_);
    const int bands = (window.j1 - window.j0 + band_rows - 1) / band_rows;
    for (int parity = 0; parity < 2; ++parity) {
        const std::size_t count = static_cast<std::size_t>((bands - parity + 1) / 2);
        parallel_for_chunks(count, 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t k = begin; k < end; ++k) {
                const int band = 2 * static_cast<int>(k) + parity;
                const int j_end = std::min(window.j1, window.j0 + (band + 1) * band_rows);
                for (int j = window.j0 + band * band_rows; j < j_end; ++j)
                    for (int i = window.i0; i < window.i1; ++i)
                        for (std::size_t d = 0; d < directions_.size(); ++d) {
                            const double* in = y.data() + d * block;
                            for_each_ray(directions_[d], {i, j},
                                         [&](const Ray& ray, bool printed, std::size_t base, std::size_t landing) {
                                             if (!printed) return;
                                             double* out = g.data() + base;
                                             for (std::size_t c = 0; c < 3; ++c) {
                                                 double v = ray.power * in[landing * 3 + c];
                                                 if (ray.core_power != 0.0) v += ray.core_power * in[cores + landing * 3 + c];
                                                 for (int n = 0; n < 4; ++n) out[ray.node[n] + c] += ray.weight[n] * v;
                                             }
                                         });
                        }
            }
        });
    }
}

std::vector<double> DisplayOperator::flat_field() const {
    std::vector<double> ones(input_size(), 1.0), out(output_size());
    forward(ones, out, 1.0);
    return out;
}

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

std::vector<Eigen::Vector2d> cell_offsets(const NodeGrid& nodes, bool between) {
    const optics::Lattice& lattice = nodes.lattice();
    const optics::CellIndex cell{0, 0};
    const Eigen::Vector2d centre = lattice.center(cell);
    std::vector<Eigen::Vector2d> offsets;
    const int shift = between ? 1 : 0;
    for (int b = 0; b < nodes.nodes_y() - shift; ++b)
        for (int a = 0; a < nodes.nodes_x() - shift; ++a) {
            const Eigen::Vector2d offset = nodes.node_offset(a, b) + 0.5 * shift * Eigen::Vector2d::Constant(nodes.spacing());
            if (lattice.cell_contains(cell, centre + offset)) offsets.push_back(offset);
        }
    return offsets;
}

SweepDirections sweep_directions(const patterns::Encoder& encoder, const NodeGrid& nodes, bool between) {
    SweepDirections out;
    const double half = 0.5 * nodes.spacing();
    const Eigen::Vector2d ex(half, 0.0), ey(0.0, half);
    double total = 0.0;
    for (const Eigen::Vector2d& offset : cell_offsets(nodes, between)) {
        out.display.push_back(encoder.incident_direction(offset));
        const Eigen::Vector3d du = encoder.incident_direction(offset + ex) - encoder.incident_direction(offset - ex);
        const Eigen::Vector3d dv = encoder.incident_direction(offset + ey) - encoder.incident_direction(offset - ey);
        out.weights.push_back(du.cross(dv).norm());
        total += out.weights.back();
    }
    for (double& w : out.weights) w = total > 0.0 ? w * static_cast<double>(out.weights.size()) / total : 1.0;
    return out;
}

std::vector<double> desired_transmittance(const patterns::Encoder& encoder, const print::ToneMap& tone,
                                          const Eigen::Vector3d& display_direction) {
    const optics::Lattice& lattice = encoder.lattice();
    const std::size_t lenslets = static_cast<std::size_t>(lattice.count_x()) * static_cast<std::size_t>(lattice.count_y());
    std::vector<double> out(lenslets * 3, 0.0);
    const Eigen::Vector3d d = display_direction.normalized();
    if (!(d.z() > 0.0)) return out;
    const Eigen::Vector3d v = encoder.options().mapping.field_direction(d);
    const relight::InterpolationWeights w = encoder.interpolator().weights(v, encoder.options().interpolation);
    const int channels = encoder.channels();
    const double scale = tone.brightness / (tone.white * d.z());
    for (int j = 0; j < lattice.count_y(); ++j)
        for (int i = 0; i < lattice.count_x(); ++i) {
            const std::size_t l = lattice.linear_index({i, j});
            for (int c = 0; c < 3; ++c) {
                double value = 0.0;
                for (std::size_t k = 0; k < w.count; ++k)
                    value += w.weight[k] * encoder.lenslet_sample({i, j}, w.index[k], channels == 3 ? c : 0);
                out[l * 3 + static_cast<std::size_t>(c)] = std::clamp(scale * value, 0.0, 1.0);
            }
        }
    return out;
}

std::vector<double> optimization_targets(const DisplayOperator& op, const std::vector<double>& flat_field,
                                         const patterns::Encoder& encoder, const print::ToneMap& tone) {
    RFD_CHECK(flat_field.size() == op.output_size());
    std::vector<double> target(op.output_size());
    const std::size_t block = op.block_size();
    parallel_for_chunks(op.directions(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t d = begin; d < end; ++d) {
            const std::vector<double> desired = desired_transmittance(encoder, tone, op.direction(d));
            for (std::size_t k = 0; k < block; ++k)
                target[d * block + k] = flat_field[d * block + k] * desired[k % desired.size()];
        }
    });
    return target;
}

std::vector<double> direct_nodes(const NodeGrid& nodes, const patterns::Encoder& encoder, const print::ToneMap& tone) {
    std::vector<double> u(nodes.size());
    const std::size_t per_lenslet = nodes.per_lenslet();
    parallel_for_chunks(per_lenslet, 4, [&](std::size_t begin, std::size_t end) {
        for (std::size_t n = begin; n < end; ++n) {
            const int a = static_cast<int>(n % static_cast<std::size_t>(nodes.nodes_x()));
            const int b = static_cast<int>(n / static_cast<std::size_t>(nodes.nodes_x()));
            const std::vector<double> desired =
                desired_transmittance(encoder, tone, encoder.incident_direction(nodes.node_offset(a, b)));
            for (std::size_t l = 0; l < nodes.lenslets(); ++l)
                for (std::size_t c = 0; c < 3; ++c) u[(l * per_lenslet + n) * 3 + c] = desired[l * 3 + c];
        }
    });
    return u;
}

std::vector<double> nodes_from_pattern(const NodeGrid& nodes, const optics::Transparency& pattern,
                                       const print::ToneMap& tone) {
    const optics::Lattice& lattice = nodes.lattice();
    std::vector<Eigen::Vector2d> points;
    points.reserve(nodes.size() / 3);
    for (int j = 0; j < lattice.count_y(); ++j)
        for (int i = 0; i < lattice.count_x(); ++i)
            for (int b = 0; b < nodes.nodes_y(); ++b)
                for (int a = 0; a < nodes.nodes_x(); ++a) points.push_back(lattice.center({i, j}) + nodes.node_offset(a, b));
    // Points in linear_index order: j outer, i inner, as the values are laid out.
    const std::size_t channels = static_cast<std::size_t>(pattern.channels());
    std::vector<float> sampled(points.size() * channels);
    pattern.sample(points, sampled);
    const double black = tone.stack_transmittance(0.0);
    std::vector<double> u(nodes.size());
    for (std::size_t p = 0; p < points.size(); ++p)
        for (std::size_t c = 0; c < 3; ++c)
            u[p * 3 + c] = std::clamp((sampled[p * channels + (channels == 3 ? c : 0)] - black) / (1.0 - black), 0.0, 1.0);
    return u;
}

std::vector<double> direction_psnr(const DisplayOperator& op, const std::vector<double>& target,
                                   std::span<const double> u, std::optional<LensletWindow> fitted) {
    const std::size_t block = op.block_size();
    const optics::Lattice& lattice = op.nodes().lattice();
    std::vector<double> psnr(op.directions());
    parallel_for_chunks(op.directions(), 1, [&](std::size_t begin, std::size_t end) {
        std::vector<double> y(block);
        for (std::size_t d = begin; d < end; ++d) {
            op.forward_direction(d, u, y);
            double peak = 0.0, sum = 0.0;
            std::size_t count = 0;
            for (int j = 0; j < lattice.count_y(); ++j)
                for (int i = 0; i < lattice.count_x(); ++i) {
                    if (fitted && !fitted->contains({i, j})) continue;
                    const std::size_t l = lattice.linear_index({i, j});
                    for (std::size_t c = 0; c < 3; ++c) {
                        const double t = target[d * block + l * 3 + c], e = y[l * 3 + c] - t;
                        peak = std::max(peak, t);
                        sum += e * e;
                        ++count;
                    }
                }
            const double mse = count ? sum / static_cast<double>(count) : 0.0;
            psnr[d] = !(peak > 0.0)  ? std::nan("")
                      : mse > 0.0 ? 10.0 * std::log10(peak * peak / mse)
                                  : std::numeric_limits<double>::infinity();
        }
    });
    return psnr;
}

NodeTransparency::NodeTransparency(const NodeGrid& nodes, std::vector<double> u, double black)
    : nodes_(nodes), u_(std::move(u)), black_(black) {
    RFD_CHECK(u_.size() == nodes.size() && black >= 0.0 && black < 1.0);
}

void NodeTransparency::sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const {
    RFD_CHECK(out.size() == points.size() * 3);
    const patterns::PatternGeometry& g = nodes_.geometry();
    parallel_for_chunks(points.size(), 1 << 12, [&](std::size_t begin, std::size_t end) {
        NodeGrid::Stencil s;
        for (std::size_t k = begin; k < end; ++k) {
            const double fx = points[k].x() / g.dot_x + 0.5 * g.width, fy = 0.5 * g.height - points[k].y() / g.dot_y;
            const bool on_sheet = fx >= 0.0 && fy >= 0.0 && fx < g.width && fy < g.height;
            const bool printed = on_sheet && nodes_.dot_stencil(static_cast<int>(fx), static_cast<int>(fy), s);
            for (std::size_t c = 0; c < 3; ++c) {
                double u = 0.0;
                if (printed)
                    for (int n = 0; n < 4; ++n) u += s.weight[n] * u_[s.index[n] + c];
                out[k * 3 + c] = on_sheet ? static_cast<float>(black_ + (1.0 - black_) * u) : 0.0f;
            }
        }
    });
}

NodePattern::NodePattern(const NodeGrid& nodes, std::vector<double> u, int channels, double white, double brightness)
    : nodes_(nodes), u_(std::move(u)), channels_(channels), scale_(white / brightness) {
    RFD_CHECK(u_.size() == nodes.size() && (channels == 1 || channels == 3) && white > 0.0 && brightness > 0.0);
}

void NodePattern::render_row(int py, std::span<float> out) const {
    const int width = nodes_.geometry().width;
    const std::size_t channels = static_cast<std::size_t>(channels_);
    RFD_CHECK(out.size() == static_cast<std::size_t>(width) * channels);
    NodeGrid::Stencil s;
    for (int px = 0; px < width; ++px) {
        float* dot = out.data() + static_cast<std::size_t>(px) * channels;
        const bool printed = nodes_.dot_stencil(px, py, s);
        for (std::size_t c = 0; c < channels; ++c) {
            double value = 0.0;
            if (printed)
                for (int n = 0; n < 4; ++n) value += s.weight[n] * u_[s.index[n] + c];
            dot[c] = static_cast<float>(value * scale_);
        }
    }
}

}  // namespace rfd::predict
