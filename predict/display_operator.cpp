#include "predict/display_operator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <Eigen/Geometry>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "predict/compare.hpp"
#include "predict/summaries.hpp"

namespace rfd::predict {

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

std::vector<double> direction_psnr(const DisplayOperator& op, const std::vector<double>& target,
                                   std::span<const double> u, std::optional<LensletWindow> fitted) {
    const std::size_t block = op.block_size();
    const optics::Lattice& lattice = op.nodes().lattice();
    std::vector<double> mse(op.directions()), peak(op.directions());
    parallel_for_chunks(op.directions(), 1, [&](std::size_t begin, std::size_t end) {
        std::vector<double> y(block);
        for (std::size_t d = begin; d < end; ++d) {
            op.forward_direction(d, u, y);
            double sum = 0.0;
            std::size_t count = 0;
            for (int j = 0; j < lattice.count_y(); ++j)
                for (int i = 0; i < lattice.count_x(); ++i) {
                    if (fitted && !fitted->contains({i, j})) continue;
                    const std::size_t l = lattice.linear_index({i, j});
                    for (std::size_t c = 0; c < 3; ++c) {
                        const double t = target[d * block + l * 3 + c], e = y[l * 3 + c] - t;
                        peak[d] = std::max(peak[d], t);
                        sum += e * e;
                        ++count;
                    }
                }
            mse[d] = count ? sum / static_cast<double>(count) : 0.0;
        }
    });
    const double field_peak = peak.empty() ? 0.0 : *std::max_element(peak.begin(), peak.end());
    std::vector<double> psnr(op.directions());
    for (std::size_t d = 0; d < psnr.size(); ++d)
        psnr[d] = psnr_against_field_db(mse[d], field_peak).value_or(std::nan(""));
    return psnr;
}

}  // namespace rfd::predict
