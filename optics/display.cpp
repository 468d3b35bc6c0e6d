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
#include "optics/cell_crossing.hpp"
#include "optics/exact.hpp"
#include "optics/paraxial.hpp"

namespace rfd::optics {
namespace {

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

// A light the display cannot show: InputError naming it (1-based, as the user gave them).
void check_lights(const std::vector<DisplayLight>& lights, const std::string& file) {
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
}

// The entry grid over a cell's bounding box: a full square grid per direction while the
// budget allows, otherwise fewer rays per direction from a low-discrepancy sequence that
// runs on from direction to direction, so together they still cover the cell.
struct EntryGrid {
    std::vector<std::vector<Eigen::Vector3d>> directions;  // per light
    std::size_t direction_count = 0;                       // over all lights
    int rays_per_side = 0;                                 // of the full grid
    double half_w = 0.0, half_h = 0.0;                     // the cell's bounding box, mm
    bool full_grid = true;
    std::size_t per_direction = 0;                         // rays per direction
    double ray_area = 0.0;                                 // mm^2 of the entrance plane per ray

    // Where ray `ray` of a direction enters, relative to the cell's centre (mm); `sequence`
    // counts the rays over all directions.
    Eigen::Vector2d offset(std::size_t ray, std::size_t sequence) const {
        if (full_grid) {
            const int n = rays_per_side;
            const int ix = static_cast<int>(ray) % n, iy = static_cast<int>(ray) / n;
            return {((ix + 0.5) / n * 2.0 - 1.0) * half_w, ((iy + 0.5) / n * 2.0 - 1.0) * half_h};
        }
        const Eigen::Vector2d u = r2_point(sequence);
        return {(2.0 * u.x() - 1.0) * half_w, (2.0 * u.y() - 1.0) * half_h};
    }
};

EntryGrid plan_entry_grid(const DesignOptics& optics, const std::vector<DisplayLight>& lights,
                          const SimulationOptions& options) {
    const Lattice& lattice = optics.lattice();
    EntryGrid grid;
    // An area light is sampled no finer than the print resolves: its disc spans about
    // 2 r B / dot dots on the pattern plane, so more directions per side than that only
    // repeat the same dots.
    const double dot_angle = optics.dot_mm().minCoeff() / std::abs(optics.paraxial_b());
    for (const DisplayLight& light : lights) {
        const int needed = static_cast<int>(std::ceil(2.0 * light.angular_radius_rad / dot_angle));
        grid.directions.push_back(disc_directions(light, std::clamp(needed, 1, options.area_samples_per_side)));
        grid.direction_count += grid.directions.back().size();
    }
    grid.rays_per_side = options.rays_per_side;
    grid.half_w = 0.5 * lattice.pitch_x();
    grid.half_h = lattice.kind() == LatticeKind::Hexagonal ? lattice.circumradius() : 0.5 * lattice.pitch_y();
    const std::size_t square =
        static_cast<std::size_t>(options.rays_per_side) * static_cast<std::size_t>(options.rays_per_side);
    grid.full_grid = grid.direction_count * square <= options.max_rays_per_lenslet;
    grid.per_direction = grid.full_grid ? square
                                        : std::max<std::size_t>(1, options.max_rays_per_lenslet /
                                                                       std::max<std::size_t>(1, grid.direction_count));
    grid.ray_area = (2.0 * grid.half_w) * (2.0 * grid.half_h) / static_cast<double>(grid.per_direction);
    return grid;
}

// One ray of the reference lenslet to trace: its direction, where it enters relative to the
// lenslet's centre, and its light's colour divided among the light's directions.
struct RayJob {
    Eigen::Vector3d direction;
    Eigen::Vector2d offset;
    std::array<double, 3> colour;
};

// Every ray of the entry grid that enters the reference lenslet's own cell.
std::vector<RayJob> reference_jobs(const DesignOptics& reference, const EntryGrid& grid,
                                   const std::vector<DisplayLight>& lights) {
    const Lattice& reference_lattice = reference.lattice();
    const CellIndex reference_cell = reference.centre_cell();
    const Eigen::Vector2d reference_centre = reference_lattice.center(reference_cell);
    std::vector<RayJob> jobs;
    std::size_t sequence = 0;
    for (std::size_t l = 0; l < lights.size(); ++l) {
        const double share = 1.0 / static_cast<double>(grid.directions[l].size());
        const std::array<double, 3> colour{lights[l].colour[0] * share, lights[l].colour[1] * share,
                                           lights[l].colour[2] * share};
        for (const Eigen::Vector3d& d : grid.directions[l])
            for (std::size_t k = 0; k < grid.per_direction; ++k) {
                const Eigen::Vector2d offset = grid.offset(k, sequence++);
                if (!reference_lattice.cell_contains(reference_cell, reference_centre + offset)) continue;
                jobs.push_back({d, offset, colour});
            }
    }
    return jobs;
}

// Traces the jobs through the reference array to the pattern and on to the diffuser's face
// (in parallel; each is independent).
std::vector<TracedRay> trace_jobs(const DesignOptics& reference, std::size_t diffuser_surface, Model model,
                                  const std::vector<RayJob>& jobs) {
    const SequentialSystem& system = reference.system();
    const Eigen::Vector2d reference_centre = reference.lattice().center(reference.centre_cell());
    const std::size_t encoding = reference.encoding_surface();
    const double entry_z = system.surfaces.front().z;
    const bool paraxial = model == Model::Paraxial;
    std::vector<TracedRay> traced(jobs.size());
    parallel_for_chunks(jobs.size(), 16, [&](std::size_t begin, std::size_t end) {
        for (std::size_t r = begin; r < end; ++r) {
            const RayJob& job = jobs[r];
            const Eigen::Vector3d& d = job.direction;
            const Eigen::Vector2d point = reference_centre + job.offset;
            TracedRay& out = traced[r];
            if (paraxial) {
                ParaxialRay ray{point.x(), point.y(), d.x() / d.z(), d.y() / d.z()};
                if (!trace_paraxial_ray(system, ray, out.visited, entry_z, 0, encoding)) continue;
                out.on_pattern = Eigen::Vector2d(ray.x, ray.y) - reference_centre;
                if (!trace_paraxial_ray(system, ray, out.visited, system.surfaces[encoding].z, encoding + 1,
                                        diffuser_surface))
                    continue;
                out.on_diffuser = Eigen::Vector2d(ray.x, ray.y) - reference_centre;
            } else {
                // Start far enough in front of the vertex plane to clear any sag.
                Ray ray{Eigen::Vector3d(point.x(), point.y(), entry_z) - (2.0 / d.z()) * d, d};
                if (!trace_exact(system, ray, out.transmittance, out.visited, 0, encoding)) continue;
                out.on_pattern = ray.origin.head<2>() - reference_centre;
                if (!trace_exact(system, ray, out.transmittance, out.visited, encoding + 1, diffuser_surface)) continue;
                out.on_diffuser = ray.origin.head<2>() - reference_centre;
            }
            out.arrived = true;
        }
    });
    return traced;
}

RepeatedRays repeated_rays(const DesignOptics& reference, const EntryGrid& grid, const std::vector<RayJob>& jobs,
                           const std::vector<TracedRay>& traced) {
    const Lattice& reference_lattice = reference.lattice();
    const CellIndex reference_cell = reference.centre_cell();
    const Eigen::Vector2d reference_centre = reference_lattice.center(reference_cell);
    RepeatedRays out;
    for (std::size_t r = 0; r < traced.size(); ++r) {
        LensletRay ray;
        ray.entering = grid.ray_area * jobs[r].direction.z();
        ray.colour = jobs[r].colour;
        out.entering += ray.entering;
        for (std::size_t c = 0; c < 3; ++c) out.entering_colour[c] += ray.entering * ray.colour[c];
        if (!traced[r].arrived) {
            ++out.lost;
            continue;
        }
        ray.on_pattern = traced[r].on_pattern;
        ray.on_diffuser = traced[r].on_diffuser;
        ray.reaching = ray.entering * traced[r].transmittance;
        ray.first_neighbour = out.neighbour_offsets.size();
        for (const CellIndex& cell : traced[r].visited)
            if (!(cell == reference_cell))
                out.neighbour_offsets.push_back(reference_lattice.center(cell) - reference_centre);
        ray.neighbours = out.neighbour_offsets.size() - ray.first_neighbour;
        ray.crossed = traced[r].visited.size() > 1;
        out.rays.push_back(ray);
    }
    std::stable_sort(out.rays.begin(), out.rays.end(),
                     [](const LensletRay& a, const LensletRay& b) { return a.on_diffuser.y() > b.on_diffuser.y(); });
    for (const LensletRay& ray : out.rays) {
        out.reach_min = out.reach_min.cwiseMin(ray.on_diffuser);
        out.reach_max = out.reach_max.cwiseMax(ray.on_diffuser);
    }
    return out;
}

// The reference lenslet's rays, traced and as every lenslet repeats them.
RepeatedRays trace_reference_lenslet(const DesignOptics& reference, std::size_t diffuser_surface, Model model,
                                     const EntryGrid& entry, const std::vector<DisplayLight>& lights) {
    const std::vector<RayJob> jobs = reference_jobs(reference, entry, lights);
    return repeated_rays(reference, entry, jobs, trace_jobs(reference, diffuser_surface, model, jobs));
}

// The output grid: the array plus one pitch of margin for light spilling past it.
struct OutputGrid {
    int width = 0, height = 0;
    double pixel_mm = 0.0;                                  // square pixels
    Eigen::Vector2d first_pixel = Eigen::Vector2d::Zero();  // centre of pixel (0, 0), mm

    std::size_t plane_size() const { return static_cast<std::size_t>(width) * static_cast<std::size_t>(height); }
    // The row, fractional, at height y_mm.
    double row(double y_mm) const { return (first_pixel.y() - y_mm) / pixel_mm; }
};

OutputGrid output_grid(const Lattice& lattice, double pixels_per_pitch) {
    OutputGrid grid;
    grid.pixel_mm = lattice.pitch_x() / pixels_per_pitch;
    const Eigen::Vector2d half = lattice.half_extent() + Eigen::Vector2d::Constant(lattice.pitch_x());
    grid.width = static_cast<int>(std::ceil(2.0 * half.x() / grid.pixel_mm));
    grid.height = static_cast<int>(std::ceil(2.0 * half.y() / grid.pixel_mm));
    grid.first_pixel =
        Eigen::Vector2d(-0.5 * (grid.width - 1) * grid.pixel_mm, 0.5 * (grid.height - 1) * grid.pixel_mm);
    return grid;
}

// Lenslet rows [j0, j1) of the display, count_x lenslets each.
struct Band {
    std::size_t j0 = 0, j1 = 0, count_x = 0;

    std::size_t cells() const { return (j1 - j0) * count_x; }
    CellIndex cell(std::size_t b) const {
        return CellIndex{static_cast<int>(b % count_x), static_cast<int>(j0 + b / count_x)};
    }
};

// The pattern under every (lenslet, ray) pair of a band, pair b * rays + r.
struct BandSamples {
    std::size_t channels = 1;  // the pattern's
    std::vector<Eigen::Vector2d> points;
    std::vector<float> transmittance;  // `channels` per pair
    std::vector<std::uint8_t> present;  // the (lenslet, ray) pair exists (its lenslets do)
};

void sample_band(const Transparency& pattern, const Lattice& lattice, const RepeatedRays& repeated, const Band& band,
                 BandSamples& samples) {
    const std::size_t band_cells = band.cells();
    const std::size_t per_cell = repeated.rays.size();
    const std::size_t pairs = band_cells * per_cell;
    samples.points.resize(pairs);
    samples.present.resize(pairs);
    samples.transmittance.resize(pairs * samples.channels);
    parallel_for_chunks(band_cells, 8, [&](std::size_t begin, std::size_t end) {
        for (std::size_t b = begin; b < end; ++b) {
            const Eigen::Vector2d centre = lattice.center(band.cell(b));
            for (std::size_t r = 0; r < per_cell; ++r) {
                const LensletRay& ray = repeated.rays[r];
                bool exists = true;
                for (std::size_t k = 0; exists && k < ray.neighbours; ++k)
                    exists = lattice.contains(
                        lattice.cell_at(centre + repeated.neighbour_offsets[ray.first_neighbour + k]));
                samples.present[b * per_cell + r] = exists;
                samples.points[b * per_cell + r] = exists ? Eigen::Vector2d(centre + ray.on_pattern)
                                                          : Eigen::Vector2d(1e30, 1e30);  // off the sheet
            }
        }
    });
    pattern.sample(samples.points, samples.transmittance);
}

// The light reaching the diffuser and the rays' fates, summed band by band in lenslet order.
struct Tally {
    double reaching = 0.0;
    std::array<double, 3> reaching_colour{};
    std::size_t rays = 0, lost = 0, crossed = 0;
};

void tally_band(const RepeatedRays& repeated, const Band& band, const BandSamples& samples, Tally& tally) {
    struct LensletSums {
        double reaching = 0.0;
        std::array<double, 3> reaching_colour{};
        std::size_t absent = 0, crossed = 0;
    };
    const std::size_t band_cells = band.cells();
    const std::size_t per_cell = repeated.rays.size();
    const std::size_t pc = samples.channels;
    // Per lenslet in parallel, summed in lenslet order.
    std::vector<LensletSums> sums(band_cells);
    parallel_for_chunks(band_cells, 8, [&](std::size_t begin, std::size_t end) {
        for (std::size_t b = begin; b < end; ++b) {
            LensletSums& sum = sums[b];
            for (std::size_t r = 0; r < per_cell; ++r) {
                const std::size_t pair = b * per_cell + r;
                const LensletRay& ray = repeated.rays[r];
                if (!samples.present[pair]) {
                    ++sum.absent;
                    continue;
                }
                if (ray.crossed) ++sum.crossed;
                sum.reaching += ray.reaching;
                const float* t = samples.transmittance.data() + pair * pc;
                for (std::size_t c = 0; c < 3; ++c)
                    sum.reaching_colour[c] += ray.reaching * ray.colour[c] * t[pc == 3 ? c : 0];
            }
        }
    });
    for (const LensletSums& sum : sums) {
        tally.reaching += sum.reaching;
        for (std::size_t c = 0; c < 3; ++c) tally.reaching_colour[c] += sum.reaching_colour[c];
        tally.lost += repeated.lost + sum.absent;
        tally.crossed += sum.crossed;
    }
    tally.rays += band_cells * (per_cell + repeated.lost);
}

// Splats a band's rays onto the diffuser, bilinearly, into `accumulated` (three planes of the
// output grid): in strips of output rows, one task per strip, each pixel summing the band's
// lenslets and rays in order, so that the image does not depend on the threads.
void splat_band(const Lattice& lattice, const RepeatedRays& repeated, const Band& band, const BandSamples& samples,
                const OutputGrid& grid, std::vector<double>& accumulated) {
    const std::vector<LensletRay>& rays = repeated.rays;
    const std::size_t band_cells = band.cells();
    const std::size_t per_cell = rays.size();
    const std::size_t pc = samples.channels;
    const std::size_t plane_size = grid.plane_size();
    const double pixel_area = grid.pixel_mm * grid.pixel_mm;
    // The output rows this band's light can reach, in strips.
    const double top_mm = lattice.center({0, static_cast<int>(band.j1 - 1)}).y() + repeated.reach_max.y();
    const double bottom_mm = lattice.center({0, static_cast<int>(band.j0)}).y() + repeated.reach_min.y();
    const int first_row = std::clamp(static_cast<int>(std::floor(grid.row(top_mm))), 0, grid.height);
    const int last_row = std::clamp(static_cast<int>(std::floor(grid.row(bottom_mm))) + 2, 0, grid.height);
    const int strips = (last_row - first_row + kStripRows - 1) / kStripRows;
    parallel_for_chunks(static_cast<std::size_t>(std::max(strips, 0)), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t s = begin; s < end; ++s) {
            const int row0 = first_row + static_cast<int>(s) * kStripRows;
            const int row1 = std::min(row0 + kStripRows, last_row);
            for (std::size_t b = 0; b < band_cells; ++b) {
                const Eigen::Vector2d centre = lattice.center(band.cell(b));
                // The run of rays that land in rows [row0 - 1, row1] (one row of margin
                // either side against rounding; the test below is exact).
                const auto first = std::partition_point(rays.begin(), rays.end(), [&](const LensletRay& ray) {
                    return grid.row(centre.y() + ray.on_diffuser.y()) < row0 - 2;
                });
                const auto last = std::partition_point(first, rays.end(), [&](const LensletRay& ray) {
                    return grid.row(centre.y() + ray.on_diffuser.y()) < row1 + 1;
                });
                for (auto it = first; it != last; ++it) {
                    const std::size_t r = static_cast<std::size_t>(it - rays.begin());
                    const std::size_t pair = b * per_cell + r;
                    if (!samples.present[pair]) continue;
                    const LensletRay& ray = *it;
                    const Eigen::Vector2d p = centre + ray.on_diffuser;
                    const double fx = (p.x() - grid.first_pixel.x()) / grid.pixel_mm;
                    const double fy = grid.row(p.y());
                    const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
                    if (y0 + 1 < row0 || y0 >= row1) continue;
                    const double tx = fx - x0, ty = fy - y0;
                    const float* t = samples.transmittance.data() + pair * pc;
                    const double row_weight[2] = {1.0 - ty, ty};
                    const double column_weight[2] = {1.0 - tx, tx};
                    for (std::size_t c = 0; c < 3; ++c) {
                        const double value = ray.reaching * ray.colour[c] * t[pc == 3 ? c : 0] / pixel_area;
                        if (value == 0.0) continue;
                        for (int dy = 0; dy < 2; ++dy) {
                            const int y = y0 + dy;
                            if (y < row0 || y >= row1) continue;
                            double* line = accumulated.data() + c * plane_size +
                                           static_cast<std::size_t>(y) * static_cast<std::size_t>(grid.width);
                            for (int dx = 0; dx < 2; ++dx) {
                                const int x = x0 + dx;
                                if (x < 0 || x >= grid.width) continue;
                                line[x] += row_weight[dy] * column_weight[dx] * value;
                            }
                        }
                    }
                }
            }
        }
    });
}

// The diffuser image from the accumulated planes, with its ray counts and efficiencies.
DiffuserImage assemble(const OutputGrid& grid, const std::vector<double>& accumulated, const EntryGrid& entry,
                       const RepeatedRays& repeated, const Tally& tally, std::size_t lenslets) {
    DiffuserImage result;
    result.pixel_mm = grid.pixel_mm;
    result.first_pixel = grid.first_pixel;
    result.directions = entry.direction_count;
    result.rays_per_direction = entry.per_direction;
    result.rays = tally.rays;
    result.lost = tally.lost;
    result.crossed = tally.crossed;
    const double entering = repeated.entering * static_cast<double>(lenslets);
    std::array<double, 3> entering_colour{};
    for (std::size_t c = 0; c < 3; ++c)
        entering_colour[c] = repeated.entering_colour[c] * static_cast<double>(lenslets);

    const std::size_t plane_size = grid.plane_size();
    result.image = Image(grid.width, grid.height, 3);
    for (int c = 0; c < 3; ++c) {
        std::span<float> plane = result.image.plane(c);
        for (std::size_t k = 0; k < plane_size; ++k)
            plane[k] = static_cast<float>(accumulated[static_cast<std::size_t>(c) * plane_size + k]);
    }
    // Reaching <= entering ray by ray; the sums run in different orders, so clamp the last
    // bit of rounding rather than report an efficiency of 1 + 1e-16.
    result.optical_efficiency = entering > 0 ? std::min(1.0, tally.reaching / entering) : 0.0;
    for (std::size_t c = 0; c < 3; ++c)
        result.pattern_efficiency[c] =
            entering_colour[c] > 0 ? std::min(1.0, tally.reaching_colour[c] / entering_colour[c]) : 0.0;
    return result;
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

RepeatedRays DisplaySimulator::trace_lenslet(const std::vector<DisplayLight>& lights,
                                            const SimulationOptions& options) const {
    RFD_CHECK(options.rays_per_side > 0 && options.max_rays_per_lenslet > 0);
    check_lights(lights, optics_.design().file);
    return trace_reference_lenslet(*reference_, diffuser_surface_, options.model,
                                   plan_entry_grid(optics_, lights, options), lights);
}

DiffuserImage DisplaySimulator::simulate(const Transparency& pattern, const std::vector<DisplayLight>& lights,
                                         const SimulationOptions& options) const {
    const Lattice& lattice = optics_.lattice();
    RFD_CHECK(options.rays_per_side > 0 && options.pixels_per_pitch > 0.0 && options.max_rays_per_lenslet > 0);
    check_lights(lights, optics_.design().file);
    const int pattern_channels = pattern.channels();
    RFD_CHECK(pattern_channels == 1 || pattern_channels == 3);

    // Every lenslet is the same and sits in the same neighbourhood of lenslets, so the rays
    // of one (the centre lenslet of a reference array) are traced once and every lenslet
    // repeats them, shifted to its centre. Only at the array's edge does a lenslet differ:
    // a ray that would cross into a lenslet beyond the edge is lost there.
    const EntryGrid entry = plan_entry_grid(optics_, lights, options);
    const RepeatedRays repeated = trace_reference_lenslet(*reference_, diffuser_surface_, options.model, entry, lights);

    const OutputGrid grid = output_grid(lattice, options.pixels_per_pitch);
    std::vector<double> accumulated(grid.plane_size() * 3, 0.0);

    // Lenslets in bands of rows: sample the pattern under every (lenslet, ray) of a band, then
    // splat onto the diffuser; the band bounds the memory of the samples.
    const std::size_t count_x = static_cast<std::size_t>(lattice.count_x());
    const std::size_t count_y = static_cast<std::size_t>(lattice.count_y());
    const std::size_t per_cell = repeated.rays.size();
    const std::size_t band_rows =
        std::clamp<std::size_t>(kPairsPerBand / std::max<std::size_t>(1, count_x * per_cell), 1, count_y);
    BandSamples samples;
    samples.channels = static_cast<std::size_t>(pattern_channels);
    Tally tally;
    for (std::size_t j0 = 0; j0 < count_y; j0 += band_rows) {
        const Band band{j0, std::min(count_y, j0 + band_rows), count_x};
        sample_band(pattern, lattice, repeated, band, samples);
        tally_band(repeated, band, samples, tally);
        if (per_cell == 0) continue;
        splat_band(lattice, repeated, band, samples, grid, accumulated);
    }
    return assemble(grid, accumulated, entry, repeated, tally, count_x * count_y);
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
