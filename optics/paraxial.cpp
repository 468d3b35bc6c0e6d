#include "optics/paraxial.hpp"

#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/parallel.hpp"

namespace rfd::optics {

RayMatrix operator*(const RayMatrix& l, const RayMatrix& e) {
    return {l.a * e.a + l.b * e.c, l.a * e.b + l.b * e.d, l.c * e.a + l.d * e.c,
            l.c * e.b + l.d * e.d};
}

RayMatrix translation(double distance) { return {1.0, distance, 0.0, 1.0}; }

RayMatrix refraction(double curvature, double n_before, double n_after) {
    return {1.0, 0.0, -(n_after - n_before) * curvature / n_after, n_before / n_after};
}

AffineRayMatrix decentred(const RayMatrix& m, double offset) {
    return {m, offset * (1.0 - m.a), -m.c * offset};
}

AffineRayMatrix operator*(const AffineRayMatrix& l, const AffineRayMatrix& e) {
    // [[L t_l][0 1]] * [[E t_e][0 1]] = [[L E, L t_e + t_l][0 1]]
    return {l.m * e.m, l.m.a * e.e + l.m.b * e.f + l.e, l.m.c * e.e + l.m.d * e.f + l.f};
}

RayMatrix vertex_matrix(const SequentialSystem& system, std::size_t first, std::size_t last) {
    RFD_CHECK(first <= last && last < system.surfaces.size());
    RayMatrix m;
    for (std::size_t s = first; s <= last; ++s) {
        const Surface& surface = system.surfaces[s];
        if (s > first) m = translation(surface.z - system.surfaces[s - 1].z) * m;
        m = refraction(curvature_of(surface.profile), system.index_in_front(s),
                       surface.index_after) *
            m;
    }
    return m;
}

CardinalPoints cardinal_points(const SequentialSystem& system, std::size_t first,
                               std::size_t last) {
    CardinalPoints p;
    p.matrix = vertex_matrix(system, first, last);
    p.n_in = system.index_in_front(first);
    p.n_out = system.surfaces[last].index_after;
    p.first_vertex_z = system.surfaces[first].z;
    p.last_vertex_z = system.surfaces[last].z;
    const RayMatrix& m = p.matrix;
    // Non-reduced slopes: u_out = C y + ..., so the power is -n_out C.
    p.power = -p.n_out * m.c;
    if (std::abs(m.c) < 1e-15) {
        p.afocal = true;
        const double nan = std::numeric_limits<double>::quiet_NaN();
        p.efl = p.rear_focal_length = p.front_focal_length = p.bfl = p.ffl = nan;
        p.front_focal_z = p.rear_focal_z = p.front_principal_z = p.rear_principal_z = nan;
        return p;
    }
    p.efl = 1.0 / p.power;
    p.rear_focal_length = p.n_out / p.power;
    p.front_focal_length = p.n_in / p.power;
    p.bfl = -m.a / m.c;  // a ray parallel to the axis crosses it here
    p.ffl = -m.d / m.c;  // a ray from here leaves parallel to the axis
    p.rear_focal_z = p.last_vertex_z + p.bfl;
    p.front_focal_z = p.first_vertex_z - p.ffl;
    p.rear_principal_z = p.rear_focal_z - p.rear_focal_length;
    p.front_principal_z = p.front_focal_z + p.front_focal_length;
    return p;
}

CardinalPoints cardinal_points(const SequentialSystem& system) {
    RFD_CHECK(!system.surfaces.empty());
    return cardinal_points(system, 0, system.surfaces.size() - 1);
}

std::optional<Conjugate> conjugate(const CardinalPoints& points, double object_distance) {
    // Full matrix from the object plane to an image plane s' behind the last vertex:
    // T(s') M T(s); the image is where its B element vanishes.
    const RayMatrix& m = points.matrix;
    const double denominator = m.c * object_distance + m.d;
    if (std::abs(denominator) < 1e-15) return std::nullopt;
    const double image = -(m.a * object_distance + m.b) / denominator;
    return Conjugate{image, m.a + image * m.c};
}

namespace {

// Per-surface data prepared once for a run of paraxial traces.
struct PreparedSurface {
    RayMatrix refraction;
    double z = 0.0;
    double semi_diameter2 = -1.0;  // < 0: no circular aperture
    const Lattice* lattice = nullptr;
    bool refracts = true;  // false for bookkeeping planes (same medium on both sides)
};

std::vector<PreparedSurface> prepare(const SequentialSystem& system, std::size_t first,
                                     std::size_t last) {
    RFD_CHECK(first <= last && last < system.surfaces.size());
    std::vector<PreparedSurface> prepared;
    for (std::size_t s = first; s <= last; ++s) {
        const Surface& surface = system.surfaces[s];
        PreparedSurface p;
        p.refraction = refraction(curvature_of(surface.profile), system.index_in_front(s),
                                  surface.index_after);
        p.z = surface.z;
        p.refracts = p.refraction.c != 0.0 || p.refraction.d != 1.0;
        RFD_DCHECK(p.refraction.a == 1.0 && p.refraction.b == 0.0);
        if (const auto* circle = std::get_if<CircularAperture>(&surface.aperture)) {
            const double limit = circle->semi_diameter * (1.0 + kApertureTolerance);
            p.semi_diameter2 = limit * limit;
        }
        if (const auto* arrayed = std::get_if<LatticeAperture>(&surface.aperture))
            p.lattice = &arrayed->lattice;
        prepared.push_back(p);
    }
    return prepared;
}

ParaxialResult trace_prepared(const std::vector<PreparedSurface>& surfaces, std::size_t first,
                              ParaxialRay ray, double z) {
    ParaxialResult result;
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    for (std::size_t k = 0; k < surfaces.size(); ++k) {
        const PreparedSurface& surface = surfaces[k];
        result.surface = static_cast<int>(first + k);
        const double distance = surface.z - z;
        ray.x += distance * ray.tx;
        ray.y += distance * ray.ty;
        z = surface.z;
        if (surface.lattice) {
            const Eigen::Vector2d point(ray.x, ray.y);
            if (!result.has_cell) {
                result.cell = surface.lattice->cell_at(point);
                result.has_cell = true;
                if (!surface.lattice->contains(result.cell)) {
                    result.status = RayStatus::Vignetted;
                    result.ray = ray;
                    return result;
                }
                centre = surface.lattice->center(result.cell);
            } else if (!surface.lattice->cell_contains(result.cell, point)) {
                result.status = RayStatus::CrossedCell;
                result.ray = ray;
                return result;
            }
        } else if (surface.semi_diameter2 >= 0.0 &&
                   ray.x * ray.x + ray.y * ray.y > surface.semi_diameter2) {
            result.status = RayStatus::Vignetted;
            result.ray = ray;
            return result;
        }
        // Refraction of a lenslet whose axis is at height h (h = 0 for centred surfaces),
        // the augmented matrix with A = 1, B = 0:  u' = C (y - h) + D u.
        // Arrayed surfaces share one lattice, so the entry lenslet's centre serves them all.
        if (surface.refracts) {
            const double hx = surface.lattice ? centre.x() : 0.0;
            const double hy = surface.lattice ? centre.y() : 0.0;
            ray.tx = surface.refraction.c * (ray.x - hx) + surface.refraction.d * ray.tx;
            ray.ty = surface.refraction.c * (ray.y - hy) + surface.refraction.d * ray.ty;
        }
    }
    result.ray = ray;
    result.status = RayStatus::Ok;
    return result;
}

}  // namespace

ParaxialResult trace_paraxial(const SequentialSystem& system, const ParaxialRay& ray,
                              double z_start, std::size_t first, std::size_t last) {
    return trace_prepared(prepare(system, first, last), first, ray, z_start);
}

void ParaxialBatch::resize(std::size_t n) {
    for (auto* v : {&x, &y, &tx, &ty}) v->resize(n);
    status.resize(n);
    cell_i.resize(n);
    cell_j.resize(n);
}

void trace_paraxial_batch(const SequentialSystem& system, ParaxialBatch& batch, double z_start,
                          std::size_t first, std::size_t last) {
    const auto surfaces = prepare(system, first, last);
    parallel_for_chunks(batch.size(), 4096, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const ParaxialResult r = trace_prepared(
                surfaces, first, {batch.x[k], batch.y[k], batch.tx[k], batch.ty[k]}, z_start);
            batch.x[k] = r.ray.x;
            batch.y[k] = r.ray.y;
            batch.tx[k] = r.ray.tx;
            batch.ty[k] = r.ray.ty;
            batch.status[k] = r.status;
            batch.cell_i[k] = r.cell.i;
            batch.cell_j[k] = r.cell.j;
        }
    });
}

}  // namespace rfd::optics
