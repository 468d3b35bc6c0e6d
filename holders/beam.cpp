#include "holders/beam.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>

#include "core/parallel.hpp"
#include "core/units.hpp"
#include "optics/analysis.hpp"
#include "optics/exact.hpp"

namespace rfd::holders {
namespace {

using optics::CellIndex;
using optics::DesignKind;

bool angular(const optics::Design& design) {
    return design.kind == DesignKind::III || design.kind == DesignKind::IV;
}

// Directions of the field of view, as unit vectors of travel: the axis and two cones.
std::vector<Eigen::Vector3d> directions(const optics::Design& design, const BeamSampling& sampling) {
    std::vector<Eigen::Vector3d> out{Eigen::Vector3d::UnitZ()};
    const double half = field_of_view_half_deg(design);
    for (const double fraction : {0.5, 0.98})
        for (int k = 0; k < sampling.azimuths; ++k)
            out.push_back(optics::incident_direction(degrees_to_radians(fraction * half),
                                                     2 * std::numbers::pi * k / sampling.azimuths));
    return out;
}

// Lenslets to trace through (I/II): the corners, the middle of each edge, their inner
// neighbours and the centre; all of them for small arrays.
std::vector<CellIndex> entry_cells(const optics::Lattice& lattice) {
    std::vector<CellIndex> out;
    const int nx = lattice.count_x(), ny = lattice.count_y();
    if (nx * ny <= 64) {
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) out.push_back({i, j});
        return out;
    }
    std::set<std::pair<int, int>> picked;
    for (const int i : {0, 1, nx / 2, nx - 2, nx - 1})
        for (const int j : {0, 1, ny / 2, ny - 2, ny - 1}) picked.insert({i, j});
    for (const auto& [i, j] : picked) out.push_back({i, j});
    return out;
}

std::string plane_of(const std::string& label) { return label.substr(0, label.find(' ')); }

}  // namespace

double field_of_view_half_deg(const optics::Design& design) {
    const optics::DesignOptics optics(design);
    double half = 89.0;
    for (const double phi : {0.0, std::numbers::pi / 2})
        if (auto a = optics::wrap_over_angle(optics, phi, optics::Model::Exact)) half = std::min(half, *a);
    return half;
}

std::vector<BeamPath> beam_paths(const optics::Design& design, const std::vector<ClearAperture>& apertures,
                                 double z_front, std::optional<double> z_exit, const BeamSampling& sampling) {
    const optics::DesignOptics optics(design);
    const optics::SequentialSystem& system = optics.system();
    const double z_entry = system.surfaces.front().z;

    // Entry points on the plane of the first vertex, each with its lenslet's centre.
    std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> entries;
    const int n = sampling.rays_per_side;
    if (!angular(design)) {
        const optics::Lattice& lattice = optics.lattice();
        for (const CellIndex cell : entry_cells(lattice)) {
            const Eigen::Vector2d c = lattice.center(cell);
            // The grid spans the cell's bounding box; points outside the cell are dropped.
            const double height = lattice.kind() == optics::LatticeKind::Hexagonal ? 2 * lattice.pitch_x() / std::sqrt(3.0)
                                                                                   : lattice.pitch_y();
            for (int v = 0; v < n; ++v)
                for (int u = 0; u < n; ++u) {
                    const Eigen::Vector2d p = c + Eigen::Vector2d(((u + 0.5) / n - 0.5) * lattice.pitch_x(),
                                                                  ((v + 0.5) / n - 0.5) * height);
                    if (lattice.cell_contains(cell, p)) entries.emplace_back(p, c);
                }
        }
    } else {
        const auto& lens = std::get<optics::LensPart>(*design.planes.front().part);
        const double r = lens.diameter / 2;
        for (int v = 0; v < n; ++v)
            for (int u = 0; u < n; ++u) {
                const Eigen::Vector2d p(((u + 0.5) / n * 2 - 1) * r, ((v + 0.5) / n * 2 - 1) * r);
                if (p.norm() <= r) entries.emplace_back(p, Eigen::Vector2d::Zero());
            }
    }

    // The clear aperture each surface must pass, if its plane has one.
    std::vector<const ClearAperture*> surface_aperture(system.surfaces.size(), nullptr);
    for (std::size_t s = 0; s < system.surfaces.size(); ++s)
        for (const ClearAperture& a : apertures)
            if (a.plane == plane_of(system.surfaces[s].label)) surface_aperture[s] = &a;

    // Each (direction, entry) in its own slot, traced in parallel, kept in this order.
    const std::vector<Eigen::Vector3d> travel = directions(design, sampling);
    std::vector<std::optional<BeamPath>> slots(travel.size() * entries.size());
    parallel_for_chunks(slots.size(), 64, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const Eigen::Vector3d& d = travel[k / entries.size()];
            const auto& [entry, cell_centre] = entries[k % entries.size()];
            // Start 1 mm in front of the holder, aimed at the entry point.
            const Eigen::Vector3d target(entry.x(), entry.y(), z_entry);
            optics::Ray ray{target - d * ((z_entry - (z_front - 1.0)) / d.z()), d};
            BeamPath path;
            path.cell_centre = cell_centre;
            path.points.reserve(system.surfaces.size() + 2);
            path.points.push_back(ray.origin + d * ((z_front - ray.origin.z()) / d.z()));
            bool kept = true;
            for (std::size_t s = 0; s < system.surfaces.size() && kept; ++s) {
                const optics::TraceResult result = optics::trace(system, ray, s, s);
                if (result.status != optics::RayStatus::Ok) {
                    kept = false;
                    break;
                }
                ray = result.ray;
                if (surface_aperture[s] && !surface_aperture[s]->contains(ray.origin.head<2>())) kept = false;
                path.points.push_back(ray.origin);
            }
            if (!kept) continue;
            if (z_exit && *z_exit > ray.origin.z() && ray.direction.z() > 0)
                path.points.push_back(ray.origin + ray.direction * ((*z_exit - ray.origin.z()) / ray.direction.z()));
            slots[k] = std::move(path);
        }
    });
    std::vector<BeamPath> paths;
    for (std::optional<BeamPath>& slot : slots)
        if (slot) paths.push_back(std::move(*slot));
    return paths;
}

Envelope envelope_at(const std::vector<BeamPath>& paths, double z, bool relative_to_cell) {
    Envelope e;
    for (const BeamPath& path : paths) {
        for (std::size_t k = 0; k + 1 < path.points.size(); ++k) {
            const Eigen::Vector3d& a = path.points[k];
            const Eigen::Vector3d& b = path.points[k + 1];
            if (z < a.z() || z > b.z() || b.z() <= a.z()) continue;
            Eigen::Vector2d p = (a + (b - a) * ((z - a.z()) / (b.z() - a.z()))).head<2>();
            if (relative_to_cell) p -= path.cell_centre;
            e.x = std::max(e.x, std::abs(p.x()));
            e.y = std::max(e.y, std::abs(p.y()));
            e.r = std::max(e.r, p.norm());
            e.empty = false;
            break;
        }
    }
    return e;
}

Envelope envelope_over(const std::vector<BeamPath>& paths, double z0, double z1, bool relative_to_cell) {
    // Along a straight segment |x|, |y| and the radius are convex in z, so their largest
    // values over the part of the segment inside [z0, z1] lie at its two ends.
    Envelope e;
    const auto include = [&](Eigen::Vector2d p, const BeamPath& path) {
        if (relative_to_cell) p -= path.cell_centre;
        e.x = std::max(e.x, std::abs(p.x()));
        e.y = std::max(e.y, std::abs(p.y()));
        e.r = std::max(e.r, p.norm());
        e.empty = false;
    };
    for (const BeamPath& path : paths) {
        for (std::size_t k = 0; k + 1 < path.points.size(); ++k) {
            const Eigen::Vector3d& a = path.points[k];
            const Eigen::Vector3d& b = path.points[k + 1];
            if (b.z() <= a.z()) continue;
            const double lo = std::max(z0, a.z()), hi = std::min(z1, b.z());
            if (lo > hi) continue;
            for (const double z : {lo, hi}) include((a + (b - a) * ((z - a.z()) / (b.z() - a.z()))).head<2>(), path);
        }
    }
    return e;
}

}  // namespace rfd::holders
