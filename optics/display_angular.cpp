#include "optics/display_angular.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Geometry>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/units.hpp"
#include "optics/cell_crossing.hpp"
#include "optics/exact.hpp"
#include "optics/paraxial.hpp"

namespace rfd::optics {
namespace {

// Exact rays start this far (mm, along z) in front of the main lens's vertex plane: its
// front bulges toward the light, so every point of it lies behind that plane.
constexpr double kLeadIn = 2.0;

// One ray's state in either model.
struct Tracked {
    Ray exact;
    ParaxialRay paraxial;
    double transmittance = 1.0;  // Fresnel, exact model
    bool arrived = false;
    bool crossed = false;
    int stopped_at = -1;  // surface where a lost ray stopped
};

void follow(const SequentialSystem& system, Model model, Tracked& state, double z_start, std::size_t first,
            std::size_t last) {
    for (int crossing = 0; crossing <= kMaxCrossings; ++crossing) {
        RayStatus status;
        int surface;
        if (model == Model::Paraxial) {
            const ParaxialResult r = trace_paraxial(system, state.paraxial, z_start, first, last);
            state.paraxial = r.ray;
            status = r.status;
            surface = r.surface;
        } else {
            const TraceResult r = trace(system, state.exact, first, last);
            state.transmittance *= r.transmittance;
            state.exact = r.ray;
            status = r.status;
            surface = r.surface;
        }
        if (status == RayStatus::Ok) {
            state.arrived = true;
            return;
        }
        state.stopped_at = surface;
        if (status != RayStatus::CrossedCell || surface < 0) break;
        state.crossed = true;
        first = static_cast<std::size_t>(surface);
        z_start = system.surfaces[first].z;
        state.exact.origin -= kRestartBackoff * state.exact.direction;
    }
    state.arrived = false;
}

Eigen::Vector2d position(const Tracked& state, Model model) {
    return model == Model::Paraxial ? Eigen::Vector2d(state.paraxial.x, state.paraxial.y)
                                    : Eigen::Vector2d(state.exact.origin.head<2>());
}

double tent(double s) { return std::max(0.0, 1.0 - std::abs(s)); }

// What one ray of the shared optics did: where it crossed the pattern, how it left.
struct Outgoing {
    Eigen::Vector2d at_pattern = Eigen::Vector2d::Zero();
    double tan_x = 0.0, tan_y = 0.0;
    double weight = 0.0;  // power / irradiance of the light: mm^2, Fresnel included
    std::size_t cell = 0; // linear index of the lenslet it left through
};

// The lights, viewpoints, distributions and ray counts of a simulation; InputError naming
// `file` and which of them otherwise.
void check_angular_inputs(const std::string& file, const std::vector<DisplayLight>& lights,
                          const AngularSimulationOptions& options, int macro_x, int macro_y) {
    auto refuse = [&](const std::string& key, const std::string& what) {
        throw InputError(SourceLocation{file, 0, 0, key}, what);
    };
    for (std::size_t i = 0; i < lights.size(); ++i) {
        const DisplayLight& light = lights[i];
        const std::string which = "light " + std::to_string(i + 1);
        if (!light.direction.allFinite() || !(light.direction.normalized().z() > 1e-9))
            refuse(which, "a light must shine through the display from behind (its direction needs z > 0)");
        for (double c : light.colour)
            if (!std::isfinite(c) || c < 0.0) refuse(which, "a light's colour must be finite and not negative");
        if (!std::isfinite(light.angular_radius_rad) || light.angular_radius_rad < 0.0 ||
            light.angular_radius_rad >= kPi / 2)
            refuse(which, "a light's angular radius must lie in [0, 90) degrees");
    }
    for (std::size_t i = 0; i < options.views.size(); ++i) {
        const Viewpoint& view = options.views[i];
        const std::string which = "view " + std::to_string(i + 1);
        if (view.eye_mm) {
            if (!view.eye_mm->allFinite() || !(view.eye_mm->z() > 0.0))
                refuse(which, "an eye must be in front of the display (z > 0 mm from its last surface)");
        } else if (!view.direction.allFinite() || !(view.direction.normalized().z() > 1e-9)) {
            refuse(which, "a view direction must point out of the display's front (z > 0)");
        }
    }
    for (std::size_t i = 0; i < options.distributions.size(); ++i) {
        const MacroPixel m = options.distributions[i];
        if (m.u < 0 || m.v < 0 || m.u >= macro_x || m.v >= macro_y)
            refuse("distribution " + std::to_string(i + 1),
                   "macro-pixel " + std::to_string(m.u) + "," + std::to_string(m.v) + " is off the " +
                       std::to_string(macro_x) + " x " + std::to_string(macro_y) + " grid");
    }
    if (options.rays_per_side < 2 || options.rays_per_side > 4096)
        refuse("rays", "rays per side must lie in [2, 4096], got " + std::to_string(options.rays_per_side));
    if (!std::isfinite(options.kernel_spacings) || options.kernel_spacings < 0.5 || options.kernel_spacings > 64)
        refuse("kernel", "the kernel radius must lie in [0.5, 64] ray spacings");
    if (options.area_samples_per_side < 1 || options.area_samples_per_side > 64)
        refuse("area samples", "area samples per side must lie in [1, 64]");
    if (options.distribution_pixels < 2 || options.distribution_pixels > 4096)
        refuse("distribution pixels", "distribution images must be 2 to 4096 pixels wide");
}

// The ray grid over the main lens's clear aperture (semi-diameter `aperture`), on its
// vertex plane: the centres of an n x n grid of squares `spacing` wide, inside the disc.
std::vector<Eigen::Vector2d> entry_grid(double aperture, int n, double spacing) {
    std::vector<Eigen::Vector2d> entries;
    for (int iy = 0; iy < n; ++iy)
        for (int ix = 0; ix < n; ++ix) {
            const Eigen::Vector2d p(-aperture + (ix + 0.5) * spacing, -aperture + (iy + 0.5) * spacing);
            if (p.norm() <= aperture) entries.push_back(p);
        }
    return entries;
}

// Where each meso-pixel sees a viewpoint: the slopes toward it, and 1 / cos^4 of the view
// angle. One per view, macro-pixel and lenslet, in that order (lenslets fastest).
struct ViewSlope {
    double tan_x = 0.0, tan_y = 0.0, inverse_cos4 = 1.0;
};
std::vector<ViewSlope> slopes_toward_views(const AngularDisplaySimulator& simulator,
                                           const std::vector<Viewpoint>& views_asked) {
    const Lattice& lattice = simulator.meso().lattice();
    const int macro_x = simulator.macro_x();
    const std::size_t cells = static_cast<std::size_t>(lattice.count_x()) * static_cast<std::size_t>(lattice.count_y());
    const std::size_t macros = static_cast<std::size_t>(macro_x) * static_cast<std::size_t>(simulator.macro_y());
    const std::size_t views = views_asked.size();
    std::vector<ViewSlope> view_slopes(views * macros * cells);
    for (std::size_t w = 0; w < views; ++w)
        for (std::size_t m = 0; m < macros; ++m)
            for (std::size_t k = 0; k < cells; ++k) {
                const Viewpoint& view = views_asked[w];
                Eigen::Vector3d d = view.direction;
                if (view.eye_mm) {
                    const MacroPixel macro{static_cast<int>(m % static_cast<std::size_t>(macro_x)),
                                           static_cast<int>(m / static_cast<std::size_t>(macro_x))};
                    const CellIndex cell{static_cast<int>(k % static_cast<std::size_t>(lattice.count_x())),
                                         static_cast<int>(k / static_cast<std::size_t>(lattice.count_x()))};
                    const Eigen::Vector2d centre = simulator.macro_centre(macro) + lattice.center(cell);
                    d = *view.eye_mm - Eigen::Vector3d(centre.x(), centre.y(), 0.0);
                }
                d.normalize();
                view_slopes[(w * macros + m) * cells + k] = {d.x() / d.z(), d.y() / d.z(), 1.0 / std::pow(d.z(), 4)};
            }

    return view_slopes;
}

// One macro-pixel's distribution sums (grid x grid x 3, rays' powers splatted with a tent of
// radius `spread` over slopes, centres from -half_tan) to relative radiance: times G^2
// (`gain2`), over the kernel's area, cos^4 of each direction and the `cells` lenslets.
Image distribution_image(const std::vector<double>& sums, int grid, double half_tan, double spread, double gain2,
                         std::size_t cells) {
    Image image(grid, grid, 3);
    const double step = 2.0 * half_tan / grid;
    for (int y = 0; y < grid; ++y)
        for (int x = 0; x < grid; ++x) {
            const double tx = -half_tan + (x + 0.5) * step, ty = half_tan - (y + 0.5) * step;
            const double cos2 = 1.0 / (1.0 + tx * tx + ty * ty);
            const double scale = gain2 / (spread * spread) / (cos2 * cos2) / static_cast<double>(cells);
            for (int c = 0; c < 3; ++c)
                image.at(x, y, c) = static_cast<float>(
                    scale * sums[(static_cast<std::size_t>(y) * grid + static_cast<std::size_t>(x)) * 3 +
                                 static_cast<std::size_t>(c)]);
        }
    return image;
}

}  // namespace

AngularDisplaySimulator::AngularDisplaySimulator(const Design& design) : optics_(design), meso_(optics_) {
    if (design.macro) {
        macro_x_ = design.macro->count_x;
        macro_y_ = design.macro->count_y;
        macro_pitch_x_ = design.macro->pitch_x;
        macro_pitch_y_ = design.macro->pitch_y;
    }
    RFD_CHECK_MSG(std::holds_alternative<CircularAperture>(optics_.system().surfaces.front().aperture),
                  "Designs III/IV begin with the main lens");
    slope_gain_ = vertex_matrix(optics_.system(), 0, meso_.last_surface()).c;
    RFD_CHECK_MSG(std::abs(slope_gain_) > 1e-12, "the display must turn main-lens position into output slope");
}

Eigen::Vector2d AngularDisplaySimulator::macro_centre(MacroPixel m) const {
    if (macro_x_ == 1 && macro_y_ == 1 && macro_pitch_x_ == 0.0) return Eigen::Vector2d::Zero();
    return {(m.u + 0.5) * macro_pitch_x_ - 0.5 * macro_x_ * macro_pitch_x_,
            (m.v + 0.5) * macro_pitch_y_ - 0.5 * macro_y_ * macro_pitch_y_};
}

AngularDisplayOutput AngularDisplaySimulator::simulate(const Transparency& pattern,
                                                       const std::vector<DisplayLight>& lights,
                                                       const AngularSimulationOptions& options) const {
    const SequentialSystem& system = optics_.system();
    const Lattice& lattice = meso_.lattice();
    check_angular_inputs(optics_.design().file, lights, options, macro_x_, macro_y_);
    const int channels = pattern.channels();
    RFD_CHECK(channels == 1 || channels == 3);

    // The ray grid over the main lens's clear aperture, on its vertex plane.
    const double aperture = std::get<CircularAperture>(system.surfaces.front().aperture).semi_diameter;
    const int n = options.rays_per_side;
    const double spacing = 2.0 * aperture / n;
    const std::vector<Eigen::Vector2d> entries = entry_grid(aperture, n, spacing);
    const std::size_t ray_count = entries.size();
    const std::size_t pattern_surface = meso_.pattern_surface(), last = meso_.last_surface();
    const double z_entry = system.surfaces.front().z, z_pattern = system.surfaces[pattern_surface].z;
    const std::size_t cells = static_cast<std::size_t>(lattice.count_x()) * static_cast<std::size_t>(lattice.count_y());
    const std::size_t macros = static_cast<std::size_t>(macro_x_) * static_cast<std::size_t>(macro_y_);
    const std::size_t views = options.views.size();

    AngularDisplayOutput result;
    result.slope_gain = slope_gain_;
    const double gain2 = slope_gain_ * slope_gain_;
    const double kernel = options.kernel_spacings * std::abs(slope_gain_) * spacing;
    result.kernel_half_tan = kernel;
    result.reference_radiance_per_sr = 1.0 / (lattice.cell_area() * gain2);
    Eigen::Vector2d half_box = Eigen::Vector2d::Zero();
    for (const auto& corner : lattice.cell_corners()) half_box = half_box.cwiseMax(corner.cwiseAbs());
    const int grid = options.distribution_pixels;
    result.distribution_half_tan = 1.25 * std::abs(meso_.output_gain()) * half_box.maxCoeff() + kernel;
    const double step = 2.0 * result.distribution_half_tan / grid;
    const double spread = std::max(kernel, step);  // a distribution pixel never falls between rays

    const std::vector<ViewSlope> view_slopes = slopes_toward_views(*this, options.views);
    // Accumulators per macro-pixel (each written by one task only).
    std::vector<std::vector<double>> view_sums(macros, std::vector<double>(views * cells * 3, 0.0));
    std::vector<std::vector<double>> distribution_sums(options.distributions.size(),
                                                       std::vector<double>(static_cast<std::size_t>(grid) * grid * 3, 0.0));
    std::vector<std::array<double, 3>> printed_power(macros, std::array<double, 3>{});
    double entering = 0.0, leaving = 0.0, crossed_power = 0.0;
    std::array<double, 3> entering_colour{};
    std::vector<double> lost_power(system.surfaces.size(), 0.0);

    std::vector<std::pair<Eigen::Vector3d, std::pair<std::array<double, 3>, double>>> directions;
    for (const DisplayLight& light : lights) {
        const auto samples = disc_directions(light, options.area_samples_per_side);
        for (const auto& d : samples) directions.push_back({d, {light.colour, 1.0 / static_cast<double>(samples.size())}});
    }
    Progress progress("simulating the display", directions.size());
    struct Traced {
        Tracked state;
        Eigen::Vector2d at_pattern = Eigen::Vector2d::Zero(), exit = Eigen::Vector2d::Zero();
        double tan_x = 0.0, tan_y = 0.0;
    };
    std::vector<Traced> rays(ray_count);
    std::vector<Outgoing> outgoing;
    std::vector<Eigen::Vector2d> points;
    std::vector<float> transmittance;
    for (const auto& entry : directions) {
        // References, not structured bindings: clang 14 (the fuzz preset) cannot capture
        // those in the lambdas below.
        const Eigen::Vector3d& d = entry.first;
        const std::array<double, 3>& colour = entry.second.first;
        const double share = entry.second.second;
        const Model model = options.model;
        // The main lens to the pattern, and on out of E: every ray independent.
        parallel_for_chunks(ray_count, 512, [&](std::size_t begin, std::size_t end) {
            for (std::size_t r = begin; r < end; ++r) {
                Traced& traced = rays[r];
                traced = Traced{};
                Tracked state;
                const Eigen::Vector3d through(entries[r].x(), entries[r].y(), z_entry);
                state.paraxial = {through.x(), through.y(), d.x() / d.z(), d.y() / d.z()};
                state.exact = Ray{through - (kLeadIn / d.z()) * d, d};
                follow(system, model, state, z_entry, 0, pattern_surface);
                if (state.arrived) {
                    traced.at_pattern = position(state, model);
                    state.arrived = false;
                    follow(system, model, state, z_pattern, pattern_surface + 1, last);
                }
                traced.state = state;
                traced.exit = position(state, model);
                if (model == Model::Paraxial) {
                    traced.tan_x = state.paraxial.tx;
                    traced.tan_y = state.paraxial.ty;
                } else {
                    const Eigen::Vector3d& o = state.exact.direction;
                    traced.tan_x = o.x() / o.z();
                    traced.tan_y = o.y() / o.z();
                }
            }
        });
        // Bookkeeping in ray order, so that sums do not depend on the threads.
        const double ray_weight = spacing * spacing * d.z();
        outgoing.clear();
        for (std::size_t r = 0; r < ray_count; ++r) {
            const Traced& traced = rays[r];
            const Tracked& state = traced.state;
            entering += ray_weight;
            for (std::size_t c = 0; c < 3; ++c) entering_colour[c] += ray_weight * colour[c] * share;
            ++result.rays;
            if (!state.arrived) {
                ++result.lost;
                if (state.stopped_at >= 0) lost_power[static_cast<std::size_t>(state.stopped_at)] += ray_weight;
                continue;
            }
            const CellIndex exit = lattice.cell_at(traced.exit);
            if (!lattice.contains(exit)) {  // on the array's very edge: count it lost there
                ++result.lost;
                lost_power[last] += ray_weight;
                continue;
            }
            const double weight = ray_weight * state.transmittance;
            leaving += weight;
            if (state.crossed) {
                ++result.crossed;
                crossed_power += weight;
            }
            outgoing.push_back({traced.at_pattern, traced.tan_x, traced.tan_y, weight * share, lattice.linear_index(exit)});
        }
        ++result.directions;

        // The dots each macro-pixel's rays cross, and what leaves it.
        const std::size_t count = outgoing.size();
        points.resize(count * macros);
        transmittance.resize(count * macros * static_cast<std::size_t>(channels));
        parallel_for_chunks(macros, 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t m = begin; m < end; ++m) {
                const MacroPixel macro{static_cast<int>(m % static_cast<std::size_t>(macro_x_)),
                                       static_cast<int>(m / static_cast<std::size_t>(macro_x_))};
                const Eigen::Vector2d centre = macro_centre(macro);
                const std::span<Eigen::Vector2d> own(points.data() + m * count, count);
                for (std::size_t r = 0; r < count; ++r) own[r] = outgoing[r].at_pattern + centre;
                const std::span<float> t(transmittance.data() + m * count * static_cast<std::size_t>(channels),
                                         count * static_cast<std::size_t>(channels));
                pattern.sample(own, t);
                std::vector<double>& sums = view_sums[m];
                std::array<double, 3>& printed = printed_power[m];
                for (std::size_t r = 0; r < count; ++r) {
                    const Outgoing& ray = outgoing[r];
                    std::array<double, 3> power{};
                    for (std::size_t c = 0; c < 3; ++c)
                        power[c] = ray.weight * colour[c] * t[r * static_cast<std::size_t>(channels) + (channels == 3 ? c : 0)];
                    for (std::size_t c = 0; c < 3; ++c) printed[c] += power[c];
                    for (std::size_t w = 0; w < views; ++w) {
                        const ViewSlope& v = view_slopes[(w * macros + m) * cells + ray.cell];
                        const double k = tent((ray.tan_x - v.tan_x) / kernel) * tent((ray.tan_y - v.tan_y) / kernel);
                        if (k == 0.0) continue;
                        for (std::size_t c = 0; c < 3; ++c) sums[(w * cells + ray.cell) * 3 + c] += k * power[c];
                    }
                    for (std::size_t q = 0; q < options.distributions.size(); ++q) {
                        if (!(options.distributions[q] == macro)) continue;
                        std::vector<double>& image = distribution_sums[q];
                        const double T = result.distribution_half_tan;
                        // Off the image (and clear of int overflow for grazing rays).
                        if (std::abs(ray.tan_x) > T + spread || std::abs(ray.tan_y) > T + spread) continue;
                        const int x0 = std::max(0, static_cast<int>(std::floor((ray.tan_x - spread + T) / step - 0.5)));
                        const int x1 = std::min(grid - 1, static_cast<int>(std::ceil((ray.tan_x + spread + T) / step - 0.5)));
                        const int y0 = std::max(0, static_cast<int>(std::floor((T - ray.tan_y - spread) / step - 0.5)));
                        const int y1 = std::min(grid - 1, static_cast<int>(std::ceil((T - ray.tan_y + spread) / step - 0.5)));
                        for (int y = y0; y <= y1; ++y)
                            for (int x = x0; x <= x1; ++x) {
                                const double node_x = -T + (x + 0.5) * step, node_y = T - (y + 0.5) * step;
                                const double k = tent((ray.tan_x - node_x) / spread) * tent((ray.tan_y - node_y) / spread);
                                if (k == 0.0) continue;
                                for (std::size_t c = 0; c < 3; ++c)
                                    image[(static_cast<std::size_t>(y) * grid + static_cast<std::size_t>(x)) * 3 + c] += k * power[c];
                            }
                    }
                }
            }
        });
        progress.advance();
    }
    progress.finish();

    // Sums to relative radiance: G^2 sum(P/E K) / cos^4, K = tent * tent / radius^2.
    const int width = macro_x_ * lattice.count_x(), height = macro_y_ * lattice.count_y();
    for (std::size_t w = 0; w < views; ++w) {
        Image image(width, height, 3);
        for (std::size_t m = 0; m < macros; ++m)
            for (std::size_t k = 0; k < cells; ++k) {
                const int u = static_cast<int>(m % static_cast<std::size_t>(macro_x_));
                const int v = static_cast<int>(m / static_cast<std::size_t>(macro_x_));
                const int i = static_cast<int>(k % static_cast<std::size_t>(lattice.count_x()));
                const int j = static_cast<int>(k / static_cast<std::size_t>(lattice.count_x()));
                const int x = u * lattice.count_x() + i;
                const int y = height - 1 - (v * lattice.count_y() + j);
                const double scale = gain2 / (kernel * kernel) * view_slopes[(w * macros + m) * cells + k].inverse_cos4;
                for (int c = 0; c < 3; ++c)
                    image.at(x, y, c) = static_cast<float>(scale * view_sums[m][(w * cells + k) * 3 + static_cast<std::size_t>(c)]);
            }
        result.views.push_back(std::move(image));
    }
    for (const std::vector<double>& sums : distribution_sums)
        result.distributions.push_back(
            distribution_image(sums, grid, result.distribution_half_tan, spread, gain2, cells));
    result.optical_efficiency = entering > 0.0 ? leaving / entering : 0.0;
    result.crossed_fraction = entering > 0.0 ? crossed_power / entering : 0.0;
    for (std::size_t c = 0; c < 3; ++c) {
        double printed = 0.0;
        for (std::size_t m = 0; m < macros; ++m) printed += printed_power[m][c];
        result.pattern_efficiency[c] =
            entering_colour[c] > 0.0 ? printed / (entering_colour[c] * static_cast<double>(macros)) : 0.0;
    }
    for (std::size_t s = 0; s < lost_power.size(); ++s)
        if (lost_power[s] > 0.0) result.lost_fraction.push_back({system.surfaces[s].label, lost_power[s] / entering});
    return result;
}

Image AngularDisplaySimulator::per_macro_pixel(const Image& view) const {
    const Lattice& lattice = meso_.lattice();
    RFD_CHECK(view.width() == macro_x_ * lattice.count_x() && view.height() == macro_y_ * lattice.count_y());
    Image out(macro_x_, macro_y_, view.channels());
    const double cells = static_cast<double>(lattice.count_x()) * lattice.count_y();
    for (int v = 0; v < macro_y_; ++v)
        for (int u = 0; u < macro_x_; ++u)
            for (int c = 0; c < view.channels(); ++c) {
                double sum = 0.0;
                for (int j = 0; j < lattice.count_y(); ++j)
                    for (int i = 0; i < lattice.count_x(); ++i)
                        sum += view.at(u * lattice.count_x() + i, (macro_y_ - 1 - v) * lattice.count_y() + j, c);
                out.at(u, macro_y_ - 1 - v, c) = static_cast<float>(sum / cells);
            }
    return out;
}

}  // namespace rfd::optics
