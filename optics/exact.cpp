#include "optics/exact.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/parallel.hpp"

namespace rfd::optics {

std::string_view to_string(RayStatus status) {
    switch (status) {
        case RayStatus::Ok: return "ok";
        case RayStatus::Missed: return "missed";
        case RayStatus::TotalInternalReflection: return "total internal reflection";
        case RayStatus::Vignetted: return "vignetted";
        case RayStatus::CrossedCell: return "crossed into neighbouring lenslet";
    }
    return "unknown";
}

namespace {

// Faces in contact (a spacer against a diffuser, two lenses whose vertices touch) meet
// where a ray that has just reached one is already on the other, up to rounding: the next
// surface's hit is accepted from this far (mm) behind the ray's origin on. Far below any
// real glass or air gap. intersect() takes a root at t ~ 0 of a curved face only where the
// ray crosses it from front to back, so a ray never meets again the face it sits on.
constexpr double kContact = 1e-9;

struct Hit {
    double t = 0.0;
    Eigen::Vector3d local;  // hit point in the vertex frame of the cap that was hit
    CellIndex cell{};
};

// Intersection with a single centred surface.
std::optional<Hit> hit_plain(const Surface& surface, const Ray& ray, double t_min) {
    const Eigen::Vector3d o = ray.origin - Eigen::Vector3d(0, 0, surface.z);
    const auto t = intersect(surface.profile, o, ray.direction, t_min);
    if (!t) return std::nullopt;
    return Hit{*t, o + *t * ray.direction, {}};
}

// Intersection with an arrayed surface: the union of one cap per cell, each clipped to
// its cell. Exact: every cap the ray can meet inside the slab the caps occupy is tested.
std::optional<Hit> hit_arrayed(const Surface& surface, const Lattice& lattice, const Ray& ray,
                               double t_min) {
    const Eigen::Vector3d& o = ray.origin;
    const Eigen::Vector3d& d = ray.direction;
    if (d.z() == 0.0) return std::nullopt;
    const double r2 = lattice.circumradius() * lattice.circumradius();
    const double edge_sag = sag(surface.profile, r2).value_or(0.0);
    const double z_lo = surface.z + std::min(0.0, edge_sag);
    const double z_hi = surface.z + std::max(0.0, edge_sag);
    double t_a = (z_lo - o.z()) / d.z();
    double t_b = (z_hi - o.z()) / d.z();
    if (t_a > t_b) std::swap(t_a, t_b);
    if (t_b <= t_min) return std::nullopt;
    t_a = std::max(t_a, t_min);
    if (!std::isfinite(t_a)) return std::nullopt;
    // Search only while the ray is over the array or the ring around it (a box a quarter
    // cell wider than the array, inside the ring): a grazing ray's path through the slab
    // can span kilometres of lattice, whose cell indices would overflow. A ray in the slab
    // beyond the box meets the sheet there, outside the array, and is vignetted.
    const Eigen::Vector2d box = lattice.half_extent() +
                                0.25 * Eigen::Vector2d(lattice.pitch_x(), lattice.pitch_y());
    double t_in = t_a, t_out = t_b;
    for (int axis = 0; axis < 2; ++axis) {
        if (d[axis] == 0.0) {
            if (std::abs(o[axis]) > box[axis]) t_in = HUGE_VAL;
            continue;
        }
        const double t0 = (-box[axis] - o[axis]) / d[axis];
        const double t1 = (box[axis] - o[axis]) / d[axis];
        t_in = std::max(t_in, std::min(t0, t1));
        t_out = std::min(t_out, std::max(t0, t1));
    }
    auto on_sheet = [&](double t) {  // a hit outside the array, at the box's edge
        const Eigen::Vector2d p = (o + t * d).head<2>().cwiseMax(-box).cwiseMin(box);
        const CellIndex cell = lattice.cell_at(p);
        const Eigen::Vector2d centre = lattice.center(cell);
        return std::optional<Hit>(
            Hit{t, o + t * d - Eigen::Vector3d(centre.x(), centre.y(), surface.z), cell});
    };
    if (t_in > t_a || t_in > t_out) return on_sheet(t_a);
    const bool leaves_box = t_out < t_b;
    t_b = std::min(t_b, t_out);
    const Eigen::Vector2d p_a = (o + t_a * d).head<2>();
    const Eigen::Vector2d p_b = (o + t_b * d).head<2>();
    const CellIndex c_a = lattice.cell_at(p_a);
    const CellIndex c_b = lattice.cell_at(p_b);

    auto try_cell = [&](CellIndex cell, std::optional<Hit>& best) {
        const Eigen::Vector2d centre = lattice.center(cell);
        const Eigen::Vector3d local_o = o - Eigen::Vector3d(centre.x(), centre.y(), surface.z);
        // The cap may be met twice (in and out through a steep side); take the first
        // crossing that lies inside this cap's own cell.
        double from = t_min;
        for (int attempt = 0; attempt < 2; ++attempt) {
            const auto t = intersect(surface.profile, local_o, d, from);
            if (!t) return;
            const Eigen::Vector3d local = local_o + *t * d;
            if (lattice.cell_contains(cell, local.head<2>() + centre)) {
                if (!best || *t < best->t) best = Hit{*t, local, cell};
                return;
            }
            from = *t;
        }
    };

    std::optional<Hit> best;
    if (c_a == c_b) {
        // Cells are convex: a segment whose ends lie in one cell stays in it.
        try_cell(c_a, best);
        return best || !leaves_box ? best : on_sheet(t_out);
    }
    const Eigen::Vector2d lo = p_a.cwiseMin(p_b);
    const Eigen::Vector2d hi = p_a.cwiseMax(p_b);
    int i_min = std::min(c_a.i, c_b.i), i_max = std::max(c_a.i, c_b.i);
    int j_min = std::min(c_a.j, c_b.j), j_max = std::max(c_a.j, c_b.j);
    for (const Eigen::Vector2d& corner : {Eigen::Vector2d(lo.x(), hi.y()),
                                         Eigen::Vector2d(hi.x(), lo.y())}) {
        const CellIndex c = lattice.cell_at(corner);
        i_min = std::min(i_min, c.i);
        i_max = std::max(i_max, c.i);
        j_min = std::min(j_min, c.j);
        j_max = std::max(j_max, c.j);
    }
    // Only the array's cells and the ring around it can be met: a grazing ray's segment
    // through the slab can span kilometres of lattice, which must not become a loop over
    // millions of cells. The ring keeps hits just outside the array (vignetted) exact.
    const int i_lo = std::max(i_min - 1, -1), i_hi = std::min(i_max + 1, lattice.count_x());
    const int j_lo = std::max(j_min - 1, -1), j_hi = std::min(j_max + 1, lattice.count_y());
    for (int j = j_lo; j <= j_hi; ++j)
        for (int i = i_lo; i <= i_hi; ++i) try_cell({i, j}, best);
    // The segment lies in the box, so every cell it crosses was tried. Without a hit, a ray
    // that leaves the box in the slab meets the sheet beyond the array there.
    return best || !leaves_box ? best : on_sheet(t_out);
}

bool inside_aperture(const Aperture& aperture, const Hit& hit, const Lattice* lattice) {
    if (const auto* circle = std::get_if<CircularAperture>(&aperture)) {
        const double limit = circle->semi_diameter * (1.0 + kApertureTolerance);
        return hit.local.head<2>().squaredNorm() <= limit * limit;
    }
    if (lattice) return lattice->contains(hit.cell);
    return true;
}

}  // namespace

TraceResult trace(const SequentialSystem& system, const Ray& ray, std::size_t first,
                  std::size_t last) {
    RFD_DCHECK(last < system.surfaces.size() && first <= last);
    TraceResult result;
    result.ray = ray;
    for (std::size_t s = first; s <= last; ++s) {
        const Surface& surface = system.surfaces[s];
        result.surface = static_cast<int>(s);
        const auto* arrayed = std::get_if<LatticeAperture>(&surface.aperture);
        const Lattice* lattice = arrayed ? &arrayed->lattice : nullptr;
        const auto hit = lattice ? hit_arrayed(surface, *lattice, result.ray, -kContact)
                                 : hit_plain(surface, result.ray, -kContact);
        if (!hit) {
            result.status = RayStatus::Missed;
            return result;
        }
        result.ray.origin += hit->t * result.ray.direction;
        if (!inside_aperture(surface.aperture, *hit, lattice)) {
            result.status = RayStatus::Vignetted;
            return result;
        }
        if (lattice) {
            if (result.has_cell && !(hit->cell == result.cell)) {
                result.status = RayStatus::CrossedCell;
                return result;
            }
            result.cell = hit->cell;
            result.has_cell = true;
        }
        const double n_before = system.index_in_front(s);
        if (n_before != surface.index_after) {
            const Eigen::Vector3d normal = normal_at(surface.profile, hit->local);
            const auto refracted =
                refract(result.ray.direction, normal, n_before / surface.index_after);
            if (!refracted) {
                result.status = RayStatus::TotalInternalReflection;
                return result;
            }
            result.transmittance *= fresnel_transmittance(
                std::abs(normal.dot(result.ray.direction)), std::abs(normal.dot(*refracted)),
                n_before, surface.index_after);
            result.ray.direction = *refracted;
        }
    }
    result.status = RayStatus::Ok;
    return result;
}

TraceResult trace(const SequentialSystem& system, const Ray& ray) {
    RFD_CHECK(!system.surfaces.empty());
    return trace(system, ray, 0, system.surfaces.size() - 1);
}

void RayBatch::resize(std::size_t n) {
    for (auto* v : {&x, &y, &z, &dx, &dy, &dz}) v->resize(n);
    status.resize(n);
    stop_surface.resize(n);
    cell_i.resize(n);
    cell_j.resize(n);
}

void RayBatch::set(std::size_t k, const Ray& ray) {
    x[k] = ray.origin.x();
    y[k] = ray.origin.y();
    z[k] = ray.origin.z();
    dx[k] = ray.direction.x();
    dy[k] = ray.direction.y();
    dz[k] = ray.direction.z();
}

Ray RayBatch::get(std::size_t k) const {
    return Ray{Eigen::Vector3d(x[k], y[k], z[k]), Eigen::Vector3d(dx[k], dy[k], dz[k])};
}

void trace_batch(const SequentialSystem& system, RayBatch& batch, std::size_t first,
                 std::size_t last) {
    RFD_CHECK(last < system.surfaces.size() && first <= last);
    parallel_for_chunks(batch.size(), 1024, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const TraceResult result = trace(system, batch.get(k), first, last);
            batch.set(k, result.ray);
            batch.status[k] = result.status;
            batch.stop_surface[k] = result.surface;
            batch.cell_i[k] = result.cell.i;
            batch.cell_j[k] = result.cell.j;
        }
    });
}

std::array<std::size_t, kRayStatusCount> count_statuses(const RayBatch& batch) {
    std::array<std::size_t, kRayStatusCount> counts{};
    for (RayStatus status : batch.status) ++counts[static_cast<std::size_t>(status)];
    return counts;
}

}  // namespace rfd::optics
