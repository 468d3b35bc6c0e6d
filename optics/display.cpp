#include "optics/display.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Geometry>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "optics/exact.hpp"
#include "optics/paraxial.hpp"

namespace rfd::optics {
namespace {

// A ray's state at a plane in either model: position, and for the exact model the whole
// ray (the paraxial one keeps its slopes).
struct RayState {
    Ray exact;
    ParaxialRay paraxial;
    double transmittance = 1.0;  // Fresnel, exact model
    bool arrived = false;
    bool crossed = false;
    Eigen::Vector2d position() const {
        return paraxial_mode ? Eigen::Vector2d(paraxial.x, paraxial.y) : Eigen::Vector2d(exact.origin.head<2>());
    }
    bool paraxial_mode = false;
};

// A ray that leaves its lenslet is restarted at the surface where it left, now in the
// lenslet it crossed into; each restart is one more cell boundary crossed.
constexpr int kMaxCrossings = 4;
// How far before a surface a restarted exact ray begins, mm: clear of its own surface.
constexpr double kRestartBackoff = 1e-7;

void trace_exact(const SequentialSystem& system, RayState& state, std::size_t first, std::size_t last) {
    for (int crossing = 0; crossing <= kMaxCrossings; ++crossing) {
        const TraceResult r = trace(system, state.exact, first, last);
        state.transmittance *= r.transmittance;
        state.exact = r.ray;
        if (r.status == RayStatus::Ok) {
            state.arrived = true;
            return;
        }
        if (r.status != RayStatus::CrossedCell) break;
        state.crossed = true;
        first = static_cast<std::size_t>(r.surface);
        state.exact.origin -= kRestartBackoff * state.exact.direction;
    }
    state.arrived = false;
}

void trace_paraxial_ray(const SequentialSystem& system, RayState& state, double z_start, std::size_t first,
                        std::size_t last) {
    for (int crossing = 0; crossing <= kMaxCrossings; ++crossing) {
        const ParaxialResult r = trace_paraxial(system, state.paraxial, z_start, first, last);
        state.paraxial = r.ray;
        if (r.status == RayStatus::Ok) {
            state.arrived = true;
            return;
        }
        if (r.status != RayStatus::CrossedCell) break;
        state.crossed = true;
        first = static_cast<std::size_t>(r.surface);
        z_start = system.surfaces[first].z;
    }
    state.arrived = false;
}

// Directions sampling one light: its own for a point source, a square grid over the disc
// of an area source (equal weights).
std::vector<Eigen::Vector3d> light_samples(const DisplayLight& light, int per_side) {
    if (light.angular_radius_rad <= 0.0 || per_side <= 1) return {light.direction};
    const Eigen::Vector3d d = light.direction.normalized();
    const Eigen::Vector3d u = d.unitOrthogonal();
    const Eigen::Vector3d v = d.cross(u);
    const double reach = std::tan(light.angular_radius_rad);
    std::vector<Eigen::Vector3d> samples;
    for (int iy = 0; iy < per_side; ++iy)
        for (int ix = 0; ix < per_side; ++ix) {
            const double fx = (ix + 0.5) / per_side * 2.0 - 1.0, fy = (iy + 0.5) / per_side * 2.0 - 1.0;
            if (fx * fx + fy * fy > 1.0) continue;
            samples.push_back((d + reach * (fx * u + fy * v)).normalized());
        }
    return samples;
}

}  // namespace

RasterTransparency::RasterTransparency(int width, int height, int channels, double dot_x, double dot_y,
                                       std::vector<float> values)
    : width_(width), height_(height), channels_(channels), dot_x_(dot_x), dot_y_(dot_y), values_(std::move(values)) {
    RFD_CHECK(width > 0 && height > 0 && channels > 0 && dot_x > 0 && dot_y > 0);
    RFD_CHECK(values_.size() == static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
                                    static_cast<std::size_t>(channels));
}

void RasterTransparency::sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const {
    const std::size_t c = static_cast<std::size_t>(channels_);
    RFD_CHECK(out.size() == points.size() * c);
    for (std::size_t k = 0; k < points.size(); ++k) {
        // The dot whose square holds the point (dot centres as in PatternGeometry).
        const double fx = points[k].x() / dot_x_ + 0.5 * width_;
        const double fy = 0.5 * height_ - points[k].y() / dot_y_;
        const bool on_sheet = fx >= 0.0 && fy >= 0.0 && fx < width_ && fy < height_;
        for (std::size_t ch = 0; ch < c; ++ch) out[k * c + ch] = 0.0f;
        if (!on_sheet) continue;
        const std::size_t index = (static_cast<std::size_t>(fy) * static_cast<std::size_t>(width_) +
                                   static_cast<std::size_t>(fx)) * c;
        for (std::size_t ch = 0; ch < c; ++ch) out[k * c + ch] = values_[index + ch];
    }
}

DisplaySimulator::DisplaySimulator(const Design& design) : optics_(design) {
    if (design.kind != DesignKind::I && design.kind != DesignKind::II)
        throw InputError(SourceLocation{design.file, 0, 0, "design.kind"},
                         "the display simulator handles Designs I and II (a diffuser shows the picture); Design " +
                             std::string(to_string(design.kind)) + " is observer-variant");
    const Plane* diffuser = design.diffuser_plane();
    RFD_CHECK(diffuser != nullptr);  // parse_design requires one for Designs I and II
    diffuser_surface_ = optics_.system().find(diffuser->name + " diffuser");
    RFD_CHECK(diffuser_surface_ > optics_.encoding_surface());
}

DiffuserImage DisplaySimulator::simulate(const Transparency& pattern, const std::vector<DisplayLight>& lights,
                                         const SimulationOptions& options) const {
    const SequentialSystem& system = optics_.system();
    const Lattice& lattice = optics_.lattice();
    const std::string& file = optics_.design().file;
    RFD_CHECK(options.rays_per_side > 0 && options.pixels_per_pitch > 0.0);
    for (std::size_t i = 0; i < lights.size(); ++i) {
        const DisplayLight& light = lights[i];
        const std::string which = "light " + std::to_string(i + 1);
        if (!light.direction.allFinite() || !(light.direction.normalized().z() > 1e-9))
            throw InputError(SourceLocation{file, 0, 0, which},
                             "a light must shine through the display from behind (its direction needs z > 0)");
        for (double c : light.colour)
            if (!std::isfinite(c) || c < 0.0)
                throw InputError(SourceLocation{file, 0, 0, which}, "a light's colour must be finite and not negative");
        if (!std::isfinite(light.angular_radius_rad) || light.angular_radius_rad < 0.0 ||
            light.angular_radius_rad >= kPi / 2)
            throw InputError(SourceLocation{file, 0, 0, which}, "a light's angular radius must lie in [0, 90) degrees");
    }
    const int pattern_channels = pattern.channels();
    RFD_CHECK(pattern_channels == 1 || pattern_channels == 3);

    // The output grid: the array plus one pitch of margin for light spilling past it.
    DiffuserImage result;
    result.pixel_mm = lattice.pitch_x() / options.pixels_per_pitch;
    const Eigen::Vector2d half = lattice.half_extent() + Eigen::Vector2d::Constant(lattice.pitch_x());
    const int width = static_cast<int>(std::ceil(2.0 * half.x() / result.pixel_mm));
    const int height = static_cast<int>(std::ceil(2.0 * half.y() / result.pixel_mm));
    result.first_pixel = Eigen::Vector2d(-0.5 * (width - 1) * result.pixel_mm, 0.5 * (height - 1) * result.pixel_mm);
    std::vector<double> accumulated(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3, 0.0);

    // Entry points of one cell, relative to its centre; every cell is the same shape.
    const double half_w = 0.5 * lattice.pitch_x();
    const double half_h = lattice.kind() == LatticeKind::Hexagonal ? lattice.circumradius() : 0.5 * lattice.pitch_y();
    const CellIndex probe = optics_.centre_cell();
    std::vector<Eigen::Vector2d> offsets;
    const int n = options.rays_per_side;
    for (int iy = 0; iy < n; ++iy)
        for (int ix = 0; ix < n; ++ix) {
            const Eigen::Vector2d offset(((ix + 0.5) / n * 2.0 - 1.0) * half_w, ((iy + 0.5) / n * 2.0 - 1.0) * half_h);
            if (lattice.cell_contains(probe, lattice.center(probe) + offset)) offsets.push_back(offset);
        }
    const double ray_area = (2.0 * half_w) * (2.0 * half_h) / (n * n);
    const std::size_t cells = static_cast<std::size_t>(lattice.count_x()) * static_cast<std::size_t>(lattice.count_y());
    const std::size_t ray_count = cells * offsets.size();
    const std::size_t encoding = optics_.encoding_surface();
    const double entry_z = system.surfaces.front().z;
    const bool paraxial = options.model == Model::Paraxial;

    double entering = 0.0, reaching = 0.0;
    std::array<double, 3> entering_colour{}, reaching_colour{};
    std::vector<RayState> rays(ray_count);
    std::vector<Eigen::Vector2d> landings(ray_count);
    std::vector<float> transmittance(ray_count * static_cast<std::size_t>(pattern_channels));
    const double pixel_area = result.pixel_mm * result.pixel_mm;
    ParaxialBatch batch;
    auto cell_of = [&](std::size_t index) {
        return CellIndex{static_cast<int>(index % static_cast<std::size_t>(lattice.count_x())),
                         static_cast<int>(index / static_cast<std::size_t>(lattice.count_x()))};
    };

    for (const DisplayLight& light : lights) {
        const std::vector<Eigen::Vector3d> samples = light_samples(light, options.area_samples_per_side);
        for (const Eigen::Vector3d& d : samples) {
            ++result.directions;
            // Lenslets to the pattern, in parallel; each ray is independent. Paraxial rays go
            // as one batch; the few that cross into a neighbouring lenslet are traced again
            // alone, through it.
            if (paraxial) {
                batch.resize(ray_count);
                parallel_for_chunks(cells, 16, [&](std::size_t begin, std::size_t end) {
                    for (std::size_t cell_index = begin; cell_index < end; ++cell_index) {
                        const Eigen::Vector2d centre = lattice.center(cell_of(cell_index));
                        for (std::size_t k = 0; k < offsets.size(); ++k) {
                            const std::size_t r = cell_index * offsets.size() + k;
                            batch.x[r] = centre.x() + offsets[k].x();
                            batch.y[r] = centre.y() + offsets[k].y();
                            batch.tx[r] = d.x() / d.z();
                            batch.ty[r] = d.y() / d.z();
                            batch.status[r] = RayStatus::Ok;
                        }
                    }
                });
                trace_paraxial_batch(system, batch, entry_z, 0, encoding);
            }
            parallel_for_chunks(cells, 16, [&](std::size_t begin, std::size_t end) {
                for (std::size_t cell_index = begin; cell_index < end; ++cell_index) {
                    const Eigen::Vector2d centre = lattice.center(cell_of(cell_index));
                    for (std::size_t k = 0; k < offsets.size(); ++k) {
                        const std::size_t r = cell_index * offsets.size() + k;
                        RayState& state = rays[r];
                        state = RayState{};
                        state.paraxial_mode = paraxial;
                        const Eigen::Vector2d point = centre + offsets[k];
                        if (paraxial) {
                            if (batch.status[r] == RayStatus::Ok) {
                                state.paraxial = {batch.x[r], batch.y[r], batch.tx[r], batch.ty[r]};
                                state.arrived = true;
                            } else if (batch.status[r] == RayStatus::CrossedCell) {
                                state.paraxial = {point.x(), point.y(), d.x() / d.z(), d.y() / d.z()};
                                trace_paraxial_ray(system, state, entry_z, 0, encoding);
                            }
                        } else {
                            const Eigen::Vector3d through(point.x(), point.y(), entry_z);
                            // Start far enough in front of the vertex plane to clear any sag.
                            state.exact = Ray{through - (2.0 / d.z()) * d, d};
                            trace_exact(system, state, 0, encoding);
                        }
                        landings[r] = state.arrived ? state.position() : Eigen::Vector2d(1e30, 1e30);  // off the sheet
                    }
                }
            });
            pattern.sample(landings, transmittance);
            // The pattern to the diffuser.
            if (paraxial) {
                parallel_for_chunks(ray_count, 4096, [&](std::size_t begin, std::size_t end) {
                    for (std::size_t r = begin; r < end; ++r) {
                        const RayState& state = rays[r];
                        batch.x[r] = state.paraxial.x;
                        batch.y[r] = state.paraxial.y;
                        batch.tx[r] = state.paraxial.tx;
                        batch.ty[r] = state.paraxial.ty;
                        batch.status[r] = state.arrived ? RayStatus::Ok : RayStatus::Vignetted;
                    }
                });
                trace_paraxial_batch(system, batch, system.surfaces[encoding].z, encoding + 1, diffuser_surface_);
            }
            parallel_for_chunks(ray_count, 1024, [&](std::size_t begin, std::size_t end) {
                for (std::size_t r = begin; r < end; ++r) {
                    RayState& state = rays[r];
                    if (!state.arrived) continue;
                    if (!paraxial) {
                        trace_exact(system, state, encoding + 1, diffuser_surface_);
                    } else if (batch.status[r] == RayStatus::Ok) {
                        state.paraxial = {batch.x[r], batch.y[r], batch.tx[r], batch.ty[r]};
                    } else if (batch.status[r] == RayStatus::CrossedCell) {
                        trace_paraxial_ray(system, state, system.surfaces[encoding].z, encoding + 1, diffuser_surface_);
                    } else {
                        state.arrived = false;
                    }
                }
            });
            // Splatted in ray order, so the sums do not depend on the threads.
            const double ray_power = ray_area * d.z();
            const double share = 1.0 / static_cast<double>(samples.size());  // of the light's colour
            for (std::size_t r = 0; r < ray_count; ++r) {
                const RayState& state = rays[r];
                entering += ray_power;
                for (std::size_t c = 0; c < 3; ++c) entering_colour[c] += ray_power * light.colour[c] * share;
                if (!state.arrived) {
                    ++result.lost;
                    continue;
                }
                if (state.crossed) ++result.crossed;
                const double power = ray_power * state.transmittance;
                reaching += power;
                const Eigen::Vector2d p = state.position();
                const double fx = (p.x() - result.first_pixel.x()) / result.pixel_mm;
                const double fy = (result.first_pixel.y() - p.y()) / result.pixel_mm;
                const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
                const double tx = fx - x0, ty = fy - y0;
                const float* t = transmittance.data() + r * static_cast<std::size_t>(pattern_channels);
                for (std::size_t c = 0; c < 3; ++c) {
                    const double value = power * light.colour[c] * share * t[pattern_channels == 3 ? c : 0];
                    reaching_colour[c] += value;
                    const double weights[4] = {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty};
                    const int xs[4] = {x0, x0 + 1, x0, x0 + 1}, ys[4] = {y0, y0, y0 + 1, y0 + 1};
                    for (int k = 0; k < 4; ++k) {
                        if (xs[k] < 0 || ys[k] < 0 || xs[k] >= width || ys[k] >= height) continue;
                        accumulated[(c * static_cast<std::size_t>(height) + static_cast<std::size_t>(ys[k])) *
                                        static_cast<std::size_t>(width) + static_cast<std::size_t>(xs[k])] +=
                            weights[k] * value / pixel_area;
                    }
                }
            }
            result.rays += ray_count;
        }
    }

    result.image = Image(width, height, 3);
    for (int c = 0; c < 3; ++c)
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                result.image.at(x, y, c) = static_cast<float>(
                    accumulated[(static_cast<std::size_t>(c) * static_cast<std::size_t>(height) + static_cast<std::size_t>(y)) *
                                    static_cast<std::size_t>(width) + static_cast<std::size_t>(x)]);
    result.optical_efficiency = entering > 0 ? reaching / entering : 0.0;
    for (std::size_t c = 0; c < 3; ++c)
        result.pattern_efficiency[c] = entering_colour[c] > 0 ? reaching_colour[c] / entering_colour[c] : 0.0;
    return result;
}

Image DisplaySimulator::per_lenslet(const DiffuserImage& image) const {
    const Lattice& lattice = optics_.lattice();
    const int count_x = lattice.count_x(), count_y = lattice.count_y();
    const int channels = image.image.channels();
    std::vector<double> sums(static_cast<std::size_t>(count_x) * static_cast<std::size_t>(count_y) *
                             static_cast<std::size_t>(channels), 0.0);
    std::vector<std::size_t> counts(static_cast<std::size_t>(count_x) * static_cast<std::size_t>(count_y), 0);
    for (int y = 0; y < image.image.height(); ++y)
        for (int x = 0; x < image.image.width(); ++x) {
            const CellIndex cell = lattice.cell_at(image.pixel_centre(x, y));
            if (!lattice.contains(cell)) continue;
            const std::size_t l = lattice.linear_index(cell);
            ++counts[l];
            for (int c = 0; c < channels; ++c)
                sums[l * static_cast<std::size_t>(channels) + static_cast<std::size_t>(c)] += image.image.at(x, y, c);
        }
    Image out(count_x, count_y, channels);
    for (int j = 0; j < count_y; ++j)
        for (int i = 0; i < count_x; ++i) {
            const std::size_t l = lattice.linear_index({i, j});
            for (int c = 0; c < channels; ++c)
                out.at(i, count_y - 1 - j, c) =
                    counts[l] ? static_cast<float>(sums[l * static_cast<std::size_t>(channels) + static_cast<std::size_t>(c)] /
                                                   static_cast<double>(counts[l]))
                              : 0.0f;
        }
    return out;
}

}  // namespace rfd::optics
