#include "optics/display.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>

#include <Eigen/Geometry>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/sequence.hpp"
#include "optics/exact.hpp"
#include "optics/paraxial.hpp"

namespace rfd::optics {
namespace {

// A ray that leaves its lenslet is restarted at the surface where it left, now in the
// lenslet it crossed into; each restart is one more cell boundary crossed.
constexpr int kMaxCrossings = 4;
// How far before a surface a restarted exact ray begins, mm: clear of its own surface.
constexpr double kRestartBackoff = 1e-7;
// Lenslets per side of the reference array the rays are traced through: a ray that crosses
// kMaxCrossings cells from its centre lenslet still meets lenslets there.
constexpr int kReferenceCells = 2 * (kMaxCrossings + 2) + 1;
// (lenslet, ray) pairs handled at once: bounds the memory of the sample points (about
// 30 bytes each); the larger, the fewer pattern rows two bands both read.
constexpr std::size_t kPairsPerBand = std::size_t{1} << 22;
// Output rows per splatting task.
constexpr int kStripRows = 16;

// Where one ray of the reference lenslet goes.
struct TracedRay {
    bool arrived = false;
    Eigen::Vector2d on_pattern = Eigen::Vector2d::Zero();   // mm, relative to the entry cell's centre
    Eigen::Vector2d on_diffuser = Eigen::Vector2d::Zero();  // likewise
    double transmittance = 1.0;                             // Fresnel, exact model
    std::vector<CellIndex> visited;  // every lenslet it passed through (the first may be a
                                     // neighbour: an oblique ray meets the curved surface
                                     // beyond its vertex plane's cell)
};

void note_visit(std::vector<CellIndex>& visited, bool has_cell, CellIndex cell) {
    if (has_cell && std::find(visited.begin(), visited.end(), cell) == visited.end()) visited.push_back(cell);
}

// Traces `ray` through surfaces [first, last] restarting it in each lenslet it crosses into.
bool trace_exact(const SequentialSystem& system, Ray& ray, double& transmittance, std::vector<CellIndex>& visited,
                 std::size_t first, std::size_t last) {
    for (int crossing = 0; crossing <= kMaxCrossings; ++crossing) {
        const TraceResult r = trace(system, ray, first, last);
        transmittance *= r.transmittance;
        ray = r.ray;
        note_visit(visited, r.has_cell, r.cell);
        if (r.status == RayStatus::Ok) return true;
        if (r.status != RayStatus::CrossedCell) return false;
        first = static_cast<std::size_t>(r.surface);
        ray.origin -= kRestartBackoff * ray.direction;
    }
    return false;
}

bool trace_paraxial_ray(const SequentialSystem& system, ParaxialRay& ray, std::vector<CellIndex>& visited,
                        double z_start, std::size_t first, std::size_t last) {
    for (int crossing = 0; crossing <= kMaxCrossings; ++crossing) {
        const ParaxialResult r = trace_paraxial(system, ray, z_start, first, last);
        ray = r.ray;
        note_visit(visited, r.has_cell, r.cell);
        if (r.status == RayStatus::Ok) return true;
        if (r.status != RayStatus::CrossedCell) return false;
        first = static_cast<std::size_t>(r.surface);
        z_start = system.surfaces[first].z;
    }
    return false;
}

// One traced ray as every lenslet of the display repeats it: what it carries and, for a
// ray that crossed into neighbouring lenslets, where those lie relative to its own.
struct LensletRay {
    Eigen::Vector2d on_pattern, on_diffuser;
    double entering = 0.0;            // power entering the lenslet: ray area x cos(incidence)
    double reaching = 0.0;            // of which reaches the diffuser (Fresnel losses)
    std::array<double, 3> colour{};   // the light's irradiance share per channel
    std::size_t first_neighbour = 0, neighbours = 0;  // into `neighbour_offsets`
    bool crossed = false;  // passed from one lenslet into another (wrap-over)
};

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
    parallel_for_chunks(points.size(), 1 << 14, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
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
    });
}

DisplaySimulator::DisplaySimulator(const Design& design)
    : optics_(design), reference_(std::make_shared<const DesignOptics>(with_lenslet_count(design, kReferenceCells, kReferenceCells))) {
    if (design.kind != DesignKind::I && design.kind != DesignKind::II)
        throw InputError(SourceLocation{design.file, 0, 0, "design.kind"},
                         "the display simulator handles Designs I and II (a diffuser shows the picture); Design " +
                             std::string(to_string(design.kind)) + " is observer-variant");
    const Plane* diffuser = design.diffuser_plane();
    RFD_CHECK(diffuser != nullptr);  // parse_design requires one for Designs I and II
    diffuser_surface_ = optics_.system().find(diffuser->name + " diffuser");
    RFD_CHECK(diffuser_surface_ > optics_.encoding_surface());
    RFD_CHECK(reference_->system().find(diffuser->name + " diffuser") == diffuser_surface_);
}

DiffuserImage DisplaySimulator::simulate(const Transparency& pattern, const std::vector<DisplayLight>& lights,
                                         const SimulationOptions& options) const {
    const Lattice& lattice = optics_.lattice();
    const std::string& file = optics_.design().file;
    RFD_CHECK(options.rays_per_side > 0 && options.pixels_per_pitch > 0.0 && options.max_rays_per_lenslet > 0);
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

    // Every lenslet is the same and sits in the same neighbourhood of lenslets, so the rays
    // of one (the centre lenslet of a reference array) are traced once and every lenslet
    // repeats them, shifted to its centre. Only at the array's edge does a lenslet differ:
    // a ray that would cross into a lenslet beyond the edge is lost there.
    const SequentialSystem& system = reference_->system();
    const Lattice& reference_lattice = reference_->lattice();
    const CellIndex reference_cell = reference_->centre_cell();
    const Eigen::Vector2d reference_centre = reference_lattice.center(reference_cell);
    const std::size_t encoding = reference_->encoding_surface();
    const double entry_z = system.surfaces.front().z;
    const bool paraxial = options.model == Model::Paraxial;

    // The entry grid over a cell's bounding box: a full square grid per direction while the
    // budget allows, otherwise fewer rays per direction from a low-discrepancy sequence that
    // runs on from direction to direction, so together they still cover the cell.
    std::vector<std::vector<Eigen::Vector3d>> directions;
    std::size_t direction_count = 0;
    // An area light is sampled no finer than the print resolves: its disc spans about
    // 2 r B / dot dots on the pattern plane, so more directions per side than that only
    // repeat the same dots.
    const double dot_angle = optics_.dot_mm().minCoeff() / std::abs(optics_.paraxial_b());
    for (const DisplayLight& light : lights) {
        const int needed = static_cast<int>(std::ceil(2.0 * light.angular_radius_rad / dot_angle));
        directions.push_back(disc_directions(light, std::clamp(needed, 1, options.area_samples_per_side)));
        direction_count += directions.back().size();
    }
    const double half_w = 0.5 * lattice.pitch_x();
    const double half_h = lattice.kind() == LatticeKind::Hexagonal ? lattice.circumradius() : 0.5 * lattice.pitch_y();
    const std::size_t grid = static_cast<std::size_t>(options.rays_per_side) * static_cast<std::size_t>(options.rays_per_side);
    const bool full_grid = direction_count * grid <= options.max_rays_per_lenslet;
    const std::size_t per_direction =
        full_grid ? grid : std::max<std::size_t>(1, options.max_rays_per_lenslet / std::max<std::size_t>(1, direction_count));
    const double ray_area = (2.0 * half_w) * (2.0 * half_h) / static_cast<double>(per_direction);
    auto entry_offset = [&](std::size_t ray, std::size_t sequence) -> Eigen::Vector2d {
        if (full_grid) {
            const int n = options.rays_per_side;
            const int ix = static_cast<int>(ray) % n, iy = static_cast<int>(ray) / n;
            return {((ix + 0.5) / n * 2.0 - 1.0) * half_w, ((iy + 0.5) / n * 2.0 - 1.0) * half_h};
        }
        const Eigen::Vector2d u = r2_point(sequence);
        return {(2.0 * u.x() - 1.0) * half_w, (2.0 * u.y() - 1.0) * half_h};
    };

    // Trace the reference lenslet's rays (in parallel; each is independent).
    struct Job {
        Eigen::Vector3d direction;
        Eigen::Vector2d offset;
        std::array<double, 3> colour;
    };
    std::vector<Job> jobs;
    std::size_t sequence = 0;
    for (std::size_t l = 0; l < lights.size(); ++l) {
        const double share = 1.0 / static_cast<double>(directions[l].size());
        const std::array<double, 3> colour{lights[l].colour[0] * share, lights[l].colour[1] * share,
                                           lights[l].colour[2] * share};
        for (const Eigen::Vector3d& d : directions[l])
            for (std::size_t k = 0; k < per_direction; ++k) {
                const Eigen::Vector2d offset = entry_offset(k, sequence++);
                if (!reference_lattice.cell_contains(reference_cell, reference_centre + offset)) continue;
                jobs.push_back({d, offset, colour});
            }
    }
    std::vector<TracedRay> traced(jobs.size());
    parallel_for_chunks(jobs.size(), 16, [&](std::size_t begin, std::size_t end) {
        for (std::size_t r = begin; r < end; ++r) {
            const Job& job = jobs[r];
            const Eigen::Vector3d& d = job.direction;
            const Eigen::Vector2d point = reference_centre + job.offset;
            TracedRay& out = traced[r];
            if (paraxial) {
                ParaxialRay ray{point.x(), point.y(), d.x() / d.z(), d.y() / d.z()};
                if (!trace_paraxial_ray(system, ray, out.visited, entry_z, 0, encoding)) continue;
                out.on_pattern = Eigen::Vector2d(ray.x, ray.y) - reference_centre;
                if (!trace_paraxial_ray(system, ray, out.visited, system.surfaces[encoding].z, encoding + 1,
                                        diffuser_surface_))
                    continue;
                out.on_diffuser = Eigen::Vector2d(ray.x, ray.y) - reference_centre;
            } else {
                // Start far enough in front of the vertex plane to clear any sag.
                Ray ray{Eigen::Vector3d(point.x(), point.y(), entry_z) - (2.0 / d.z()) * d, d};
                if (!trace_exact(system, ray, out.transmittance, out.visited, 0, encoding)) continue;
                out.on_pattern = ray.origin.head<2>() - reference_centre;
                if (!trace_exact(system, ray, out.transmittance, out.visited, encoding + 1, diffuser_surface_)) continue;
                out.on_diffuser = ray.origin.head<2>() - reference_centre;
            }
            out.arrived = true;
        }
    });

    // What every lenslet repeats: the rays that reach the diffuser, sorted by where they
    // land along y (so the rays of a lenslet that land in a strip of output rows are a
    // contiguous run), and the light entering it in all.
    std::vector<LensletRay> rays;
    std::vector<Eigen::Vector2d> neighbour_offsets;
    double entering_per_lenslet = 0.0;
    std::array<double, 3> entering_colour_per_lenslet{};
    std::size_t lost_per_lenslet = 0;
    for (std::size_t r = 0; r < traced.size(); ++r) {
        LensletRay ray;
        ray.entering = ray_area * jobs[r].direction.z();
        ray.colour = jobs[r].colour;
        entering_per_lenslet += ray.entering;
        for (std::size_t c = 0; c < 3; ++c) entering_colour_per_lenslet[c] += ray.entering * ray.colour[c];
        if (!traced[r].arrived) {
            ++lost_per_lenslet;
            continue;
        }
        ray.on_pattern = traced[r].on_pattern;
        ray.on_diffuser = traced[r].on_diffuser;
        ray.reaching = ray.entering * traced[r].transmittance;
        ray.first_neighbour = neighbour_offsets.size();
        for (const CellIndex& cell : traced[r].visited)
            if (!(cell == reference_cell)) neighbour_offsets.push_back(reference_lattice.center(cell) - reference_centre);
        ray.neighbours = neighbour_offsets.size() - ray.first_neighbour;
        ray.crossed = traced[r].visited.size() > 1;
        rays.push_back(ray);
    }
    std::stable_sort(rays.begin(), rays.end(),
                     [](const LensletRay& a, const LensletRay& b) { return a.on_diffuser.y() > b.on_diffuser.y(); });
    Eigen::Vector2d reach_min = Eigen::Vector2d::Constant(HUGE_VAL), reach_max = -reach_min;
    for (const LensletRay& ray : rays) {
        reach_min = reach_min.cwiseMin(ray.on_diffuser);
        reach_max = reach_max.cwiseMax(ray.on_diffuser);
    }

    // The output grid: the array plus one pitch of margin for light spilling past it.
    DiffuserImage result;
    result.pixel_mm = lattice.pitch_x() / options.pixels_per_pitch;
    const Eigen::Vector2d half = lattice.half_extent() + Eigen::Vector2d::Constant(lattice.pitch_x());
    const int width = static_cast<int>(std::ceil(2.0 * half.x() / result.pixel_mm));
    const int height = static_cast<int>(std::ceil(2.0 * half.y() / result.pixel_mm));
    result.first_pixel = Eigen::Vector2d(-0.5 * (width - 1) * result.pixel_mm, 0.5 * (height - 1) * result.pixel_mm);
    result.directions = direction_count;
    result.rays_per_direction = per_direction;
    const std::size_t plane_size = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    std::vector<double> accumulated(plane_size * 3, 0.0);
    const double pixel_area = result.pixel_mm * result.pixel_mm;
    auto pixel_row = [&](double y_mm) { return (result.first_pixel.y() - y_mm) / result.pixel_mm; };

    // Lenslets in bands of rows: sample the pattern under every (lenslet, ray) of a band, then
    // splat onto the diffuser in strips of output rows, one task per strip; each pixel sums
    // its band's lenslets and rays in order, so the image does not depend on the threads.
    const std::size_t count_x = static_cast<std::size_t>(lattice.count_x());
    const std::size_t count_y = static_cast<std::size_t>(lattice.count_y());
    const std::size_t per_cell = rays.size();
    const std::size_t band_rows =
        std::clamp<std::size_t>(kPairsPerBand / std::max<std::size_t>(1, count_x * per_cell), 1, count_y);
    const std::size_t pc = static_cast<std::size_t>(pattern_channels);
    std::vector<Eigen::Vector2d> points;
    std::vector<float> transmittance;
    std::vector<std::uint8_t> present;  // the (lenslet, ray) pair exists (its lenslets do)
    struct LensletSums {
        double reaching = 0.0;
        std::array<double, 3> reaching_colour{};
        std::size_t absent = 0, crossed = 0;
    };
    std::vector<LensletSums> sums;
    double reaching = 0.0;
    std::array<double, 3> reaching_colour{};
    for (std::size_t j0 = 0; j0 < count_y; j0 += band_rows) {
        const std::size_t j1 = std::min(count_y, j0 + band_rows);
        const std::size_t band_cells = (j1 - j0) * count_x;
        const std::size_t pairs = band_cells * per_cell;
        points.resize(pairs);
        present.resize(pairs);
        transmittance.resize(pairs * pc);
        auto cell_of = [&](std::size_t b) {
            return CellIndex{static_cast<int>(b % count_x), static_cast<int>(j0 + b / count_x)};
        };
        parallel_for_chunks(band_cells, 8, [&](std::size_t begin, std::size_t end) {
            for (std::size_t b = begin; b < end; ++b) {
                const Eigen::Vector2d centre = lattice.center(cell_of(b));
                for (std::size_t r = 0; r < per_cell; ++r) {
                    const LensletRay& ray = rays[r];
                    bool exists = true;
                    for (std::size_t k = 0; exists && k < ray.neighbours; ++k)
                        exists = lattice.contains(lattice.cell_at(centre + neighbour_offsets[ray.first_neighbour + k]));
                    present[b * per_cell + r] = exists;
                    points[b * per_cell + r] = exists ? Eigen::Vector2d(centre + ray.on_pattern)
                                                      : Eigen::Vector2d(1e30, 1e30);  // off the sheet
                }
            }
        });
        pattern.sample(points, transmittance);

        // Bookkeeping per lenslet in parallel, summed in lenslet order.
        sums.assign(band_cells, LensletSums{});
        parallel_for_chunks(band_cells, 8, [&](std::size_t begin, std::size_t end) {
            for (std::size_t b = begin; b < end; ++b) {
                LensletSums& sum = sums[b];
                for (std::size_t r = 0; r < per_cell; ++r) {
                    const std::size_t pair = b * per_cell + r;
                    const LensletRay& ray = rays[r];
                    if (!present[pair]) {
                        ++sum.absent;
                        continue;
                    }
                    if (ray.crossed) ++sum.crossed;
                    sum.reaching += ray.reaching;
                    const float* t = transmittance.data() + pair * pc;
                    for (std::size_t c = 0; c < 3; ++c)
                        sum.reaching_colour[c] += ray.reaching * ray.colour[c] * t[pc == 3 ? c : 0];
                }
            }
        });
        for (const LensletSums& sum : sums) {
            reaching += sum.reaching;
            for (std::size_t c = 0; c < 3; ++c) reaching_colour[c] += sum.reaching_colour[c];
            result.lost += lost_per_lenslet + sum.absent;
            result.crossed += sum.crossed;
        }
        result.rays += band_cells * (per_cell + lost_per_lenslet);
        if (per_cell == 0) continue;

        // The output rows this band's light can reach, in strips.
        const double top_mm = lattice.center({0, static_cast<int>(j1 - 1)}).y() + reach_max.y();
        const double bottom_mm = lattice.center({0, static_cast<int>(j0)}).y() + reach_min.y();
        const int first_row = std::clamp(static_cast<int>(std::floor(pixel_row(top_mm))), 0, height);
        const int last_row = std::clamp(static_cast<int>(std::floor(pixel_row(bottom_mm))) + 2, 0, height);
        const int strips = (last_row - first_row + kStripRows - 1) / kStripRows;
        parallel_for_chunks(static_cast<std::size_t>(std::max(strips, 0)), 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t s = begin; s < end; ++s) {
                const int row0 = first_row + static_cast<int>(s) * kStripRows;
                const int row1 = std::min(row0 + kStripRows, last_row);
                for (std::size_t b = 0; b < band_cells; ++b) {
                    const Eigen::Vector2d centre = lattice.center(cell_of(b));
                    // The run of rays that land in rows [row0 - 1, row1] (one row of margin
                    // either side against rounding; the test below is exact).
                    const auto first = std::partition_point(rays.begin(), rays.end(), [&](const LensletRay& ray) {
                        return pixel_row(centre.y() + ray.on_diffuser.y()) < row0 - 2;
                    });
                    const auto last = std::partition_point(first, rays.end(), [&](const LensletRay& ray) {
                        return pixel_row(centre.y() + ray.on_diffuser.y()) < row1 + 1;
                    });
                    for (auto it = first; it != last; ++it) {
                        const std::size_t r = static_cast<std::size_t>(it - rays.begin());
                        const std::size_t pair = b * per_cell + r;
                        if (!present[pair]) continue;
                        const LensletRay& ray = *it;
                        const Eigen::Vector2d p = centre + ray.on_diffuser;
                        const double fx = (p.x() - result.first_pixel.x()) / result.pixel_mm;
                        const double fy = pixel_row(p.y());
                        const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
                        if (y0 + 1 < row0 || y0 >= row1) continue;
                        const double tx = fx - x0, ty = fy - y0;
                        const float* t = transmittance.data() + pair * pc;
                        const double row_weight[2] = {1.0 - ty, ty};
                        const double column_weight[2] = {1.0 - tx, tx};
                        for (std::size_t c = 0; c < 3; ++c) {
                            const double value = ray.reaching * ray.colour[c] * t[pc == 3 ? c : 0] / pixel_area;
                            if (value == 0.0) continue;
                            for (int dy = 0; dy < 2; ++dy) {
                                const int y = y0 + dy;
                                if (y < row0 || y >= row1) continue;
                                double* line = accumulated.data() + c * plane_size +
                                               static_cast<std::size_t>(y) * static_cast<std::size_t>(width);
                                for (int dx = 0; dx < 2; ++dx) {
                                    const int x = x0 + dx;
                                    if (x < 0 || x >= width) continue;
                                    line[x] += row_weight[dy] * column_weight[dx] * value;
                                }
                            }
                        }
                    }
                }
            }
        });
    }
    const double entering = entering_per_lenslet * static_cast<double>(count_x * count_y);
    std::array<double, 3> entering_colour{};
    for (std::size_t c = 0; c < 3; ++c)
        entering_colour[c] = entering_colour_per_lenslet[c] * static_cast<double>(count_x * count_y);

    result.image = Image(width, height, 3);
    for (int c = 0; c < 3; ++c) {
        std::span<float> plane = result.image.plane(c);
        for (std::size_t k = 0; k < plane_size; ++k)
            plane[k] = static_cast<float>(accumulated[static_cast<std::size_t>(c) * plane_size + k]);
    }
    // Reaching <= entering ray by ray; the sums run in different orders, so clamp the last
    // bit of rounding rather than report an efficiency of 1 + 1e-16.
    result.optical_efficiency = entering > 0 ? std::min(1.0, reaching / entering) : 0.0;
    for (std::size_t c = 0; c < 3; ++c)
        result.pattern_efficiency[c] =
            entering_colour[c] > 0 ? std::min(1.0, reaching_colour[c] / entering_colour[c]) : 0.0;
    return result;
}

PictureContrast picture_contrast(const Image& per_lenslet, const DiffuserScatter& diffuser,
                                 std::span<const double> front_ratios) {
    RFD_CHECK(!per_lenslet.empty());
    std::vector<double> luminance;
    for (int y = 0; y < per_lenslet.height(); ++y)
        for (int x = 0; x < per_lenslet.width(); ++x) {
            if (per_lenslet.channels() < 3) {
                luminance.push_back(per_lenslet.at(x, y, 0));
                continue;
            }
            luminance.push_back(0.2126 * per_lenslet.at(x, y, 0) + 0.7152 * per_lenslet.at(x, y, 1) +
                                0.0722 * per_lenslet.at(x, y, 2));
        }
    std::sort(luminance.begin(), luminance.end());
    auto percentile = [&](double p) {
        return luminance[static_cast<std::size_t>(std::lround(p * static_cast<double>(luminance.size() - 1)))];
    };
    PictureContrast out;
    out.white = percentile(0.99);
    out.black = percentile(0.01);
    out.transmissivity = diffuser.transmittance * out.white;
    for (double r : front_ratios) {
        const double bright = diffuser.transmittance * out.white + diffuser.reflectance * r;
        const double dark = diffuser.transmittance * out.black + diffuser.reflectance * r;
        out.with_front.push_back({r, dark > 0.0 ? bright / dark : HUGE_VAL});
    }
    return out;
}

std::vector<Eigen::Vector3d> disc_directions(const DisplayLight& light, int per_side) {
    if (light.angular_radius_rad <= 0.0 || per_side <= 1) return {light.direction.normalized()};
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

Image per_lenslet(const Lattice& lattice, const DiffuserImage& image, double core_fraction) {
    RFD_CHECK(core_fraction > 0.0 && core_fraction <= 1.0);
    const int count_x = lattice.count_x(), count_y = lattice.count_y();
    const int channels = image.image.channels();
    const std::size_t lenslets = static_cast<std::size_t>(count_x) * static_cast<std::size_t>(count_y);
    std::vector<double> sums(lenslets * static_cast<std::size_t>(channels), 0.0);
    std::vector<std::size_t> counts(lenslets, 0);
    for (int y = 0; y < image.image.height(); ++y)
        for (int x = 0; x < image.image.width(); ++x) {
            const Eigen::Vector2d p = image.pixel_centre(x, y);
            const CellIndex cell = lattice.cell_at(p);
            if (!lattice.contains(cell)) continue;
            const Eigen::Vector2d centre = lattice.center(cell);
            if (core_fraction < 1.0 && !lattice.cell_contains(cell, centre + (p - centre) / core_fraction)) continue;
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

Image DisplaySimulator::per_lenslet(const DiffuserImage& image) const { return optics::per_lenslet(optics_.lattice(), image); }

}  // namespace rfd::optics
