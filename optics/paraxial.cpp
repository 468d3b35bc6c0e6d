#include "optics/paraxial.hpp"

#include <algorithm>
#include <array>
#include <bit>
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

// A run of paraxial traces is prepared once: surfaces that test nothing (no aperture, no
// lattice) are folded, with the transfers around them, into the transfer matrix of the
// next surface that does. They are centred (only arrayed surfaces are decentred), so the
// folding is exact; a ray then costs one 2x2 product and one test per checking surface.
struct Stage {
    RayMatrix transfer;            // from the previous stage's plane to this surface's
    RayMatrix refraction;          // this surface's, applied about the lenslet axis
    double semi_diameter2 = -1.0;  // < 0: no circular aperture
    const Lattice* lattice = nullptr;
    int surface = 0;               // index in the system, for the result
    bool refracts = true;          // false for bookkeeping planes (same medium both sides)
};

std::vector<Stage> prepare(const SequentialSystem& system, double z_start, std::size_t first,
                           std::size_t last) {
    RFD_CHECK(first <= last && last < system.surfaces.size());
    std::vector<Stage> stages;
    RayMatrix pending = translation(system.surfaces[first].z - z_start);
    for (std::size_t s = first; s <= last; ++s) {
        const Surface& surface = system.surfaces[s];
        Stage stage;
        stage.refraction = refraction(curvature_of(surface.profile), system.index_in_front(s),
                                      surface.index_after);
        RFD_DCHECK(stage.refraction.a == 1.0 && stage.refraction.b == 0.0);
        if (const auto* circle = std::get_if<CircularAperture>(&surface.aperture)) {
            const double limit = circle->semi_diameter * (1.0 + kApertureTolerance);
            stage.semi_diameter2 = limit * limit;
        }
        if (const auto* arrayed = std::get_if<LatticeAperture>(&surface.aperture))
            stage.lattice = &arrayed->lattice;
        const bool tests = stage.lattice || stage.semi_diameter2 >= 0.0;
        const double to_next = s < last ? system.surfaces[s + 1].z - surface.z : 0.0;
        if (!tests && s < last) {
            pending = translation(to_next) * stage.refraction * pending;
            continue;
        }
        stage.transfer = pending;
        stage.surface = static_cast<int>(s);
        stage.refracts = stage.refraction.c != 0.0 || stage.refraction.d != 1.0;
        stages.push_back(stage);
        pending = translation(to_next);
    }
    return stages;
}

ParaxialResult trace_prepared(const std::vector<Stage>& stages, ParaxialRay ray) {
    ParaxialResult result;
    double hx = 0.0, hy = 0.0;  // axis of the lenslet entered (0 for centred surfaces)
    for (const Stage& stage : stages) {
        result.surface = stage.surface;
        const RayMatrix& m = stage.transfer;
        ray = {m.a * ray.x + m.b * ray.tx, m.a * ray.y + m.b * ray.ty,
               m.c * ray.x + m.d * ray.tx, m.c * ray.y + m.d * ray.ty};
        if (stage.lattice) {
            const Eigen::Vector2d point(ray.x, ray.y);
            if (!result.has_cell) {
                result.cell = stage.lattice->cell_at(point);
                result.has_cell = true;
                if (!stage.lattice->contains(result.cell)) {
                    result.status = RayStatus::Vignetted;
                    result.ray = ray;
                    return result;
                }
                const Eigen::Vector2d centre = stage.lattice->center(result.cell);
                hx = centre.x();
                hy = centre.y();
            } else if (!stage.lattice->cell_contains(result.cell, point)) {
                result.status = RayStatus::CrossedCell;
                result.ray = ray;
                return result;
            }
        } else if (stage.semi_diameter2 >= 0.0 &&
                   ray.x * ray.x + ray.y * ray.y > stage.semi_diameter2) {
            result.status = RayStatus::Vignetted;
            result.ray = ray;
            return result;
        }
        // Refraction about the lenslet's axis at height h: the augmented matrix with
        // A = 1, B = 0 gives u' = C (y - h) + D u. Arrayed surfaces share one lattice, so
        // the entry lenslet's axis serves them all; centred surfaces use h = 0.
        if (stage.refracts) {
            const double ax = stage.lattice ? hx : 0.0;
            const double ay = stage.lattice ? hy : 0.0;
            ray.tx = stage.refraction.c * (ray.x - ax) + stage.refraction.d * ray.tx;
            ray.ty = stage.refraction.c * (ray.y - ay) + stage.refraction.d * ray.ty;
        }
    }
    result.ray = ray;
    result.status = RayStatus::Ok;
    return result;
}

}  // namespace

ParaxialResult trace_paraxial(const SequentialSystem& system, const ParaxialRay& ray,
                              double z_start, std::size_t first, std::size_t last) {
    return trace_prepared(prepare(system, z_start, first, last), ray);
}

void ParaxialBatch::resize(std::size_t n) {
    for (auto* v : {&x, &y, &tx, &ty}) v->resize(n);
    status.resize(n);
    cell_i.resize(n);
    cell_j.resize(n);
}

namespace {

// One stage applied to a run of rays [0, n) of a batch. The loops run stage by stage
// rather than ray by ray: each is a straight pass over arrays with no per-ray dispatch,
// and a ray that has already stopped is carried through unchanged by selects, not
// branches (rays stop at random places, so branches would mispredict). The arithmetic is
// that of trace_prepared(), term for term, so both give bit-identical rays.
struct BatchView {
    double* x;
    double* y;
    double* tx;
    double* ty;
    RayStatus* status;
    std::int32_t* cell_i;
    std::int32_t* cell_j;
    double* axis_x;  // axis of the lenslet entered (0 until one is)
    double* axis_y;
};

// Branch-free selects as bit masks. GCC turns `x[k] = alive ? new : x[k]` into a
// conditional store, which it cannot vectorise without AVX; bitwise blends it can.
inline std::uint64_t mask64(bool condition) { return -static_cast<std::uint64_t>(condition); }
inline std::uint32_t mask32(bool condition) { return -static_cast<std::uint32_t>(condition); }
inline double select(std::uint64_t mask, double if_set, double otherwise) {
    return std::bit_cast<double>((std::bit_cast<std::uint64_t>(if_set) & mask) |
                                 (std::bit_cast<std::uint64_t>(otherwise) & ~mask));
}
inline std::int32_t select(std::uint32_t mask, std::int32_t if_set, std::int32_t otherwise) {
    return static_cast<std::int32_t>((static_cast<std::uint32_t>(if_set) & mask) |
                                     (static_cast<std::uint32_t>(otherwise) & ~mask));
}
inline RayStatus stop_if(bool alive, bool stops, RayStatus reason, RayStatus current) {
    const auto m = static_cast<std::uint8_t>(-static_cast<int>(alive && stops));
    return static_cast<RayStatus>((static_cast<std::uint8_t>(reason) & m) |
                                  (static_cast<std::uint8_t>(current) & static_cast<std::uint8_t>(~m)));
}

// A ray meets its first arrayed surface: it enters the lenslet whose cell it hits, or is
// vignetted outside the array.
template <LatticeKind K>
void enter_lattice(const Lattice& lattice, const BatchView& v, std::size_t n) {
    const double* __restrict px = v.x;
    const double* __restrict py = v.y;
    RayStatus* __restrict status = v.status;
    std::int32_t* __restrict cell_i = v.cell_i;
    std::int32_t* __restrict cell_j = v.cell_j;
    double* __restrict axis_x = v.axis_x;
    double* __restrict axis_y = v.axis_y;
    for (std::size_t k = 0; k < n; ++k) {
        const bool alive = status[k] == RayStatus::Ok;
        const CellIndex cell = lattice.cell_at_of<K>({px[k], py[k]});
        const Eigen::Vector2d centre = lattice.center_of<K>(cell);
        cell_i[k] = select(mask32(alive), cell.i, cell_i[k]);
        cell_j[k] = select(mask32(alive), cell.j, cell_j[k]);
        axis_x[k] = select(mask64(alive), centre.x(), axis_x[k]);
        axis_y[k] = select(mask64(alive), centre.y(), axis_y[k]);
        status[k] = stop_if(alive, !lattice.contains(cell), RayStatus::Vignetted, status[k]);
    }
}

// Later arrayed surfaces: the ray must still be inside the lenslet it entered.
template <LatticeKind K>
void stay_in_cell(const Lattice& lattice, const BatchView& v, std::size_t n) {
    const double* __restrict px = v.x;
    const double* __restrict py = v.y;
    RayStatus* __restrict status = v.status;
    const std::int32_t* __restrict cell_i = v.cell_i;
    const std::int32_t* __restrict cell_j = v.cell_j;
    for (std::size_t k = 0; k < n; ++k) {
        const bool alive = status[k] == RayStatus::Ok;
        const bool stays = lattice.cell_contains_of<K>({cell_i[k], cell_j[k]}, {px[k], py[k]});
        status[k] = stop_if(alive, !stays, RayStatus::CrossedCell, status[k]);
    }
}

// Compiled twice: for AVX2 machines (x86-64-v3) and for the x86-64 baseline, chosen at
// load time. ISO C++ mode keeps floating-point contraction off, so both clones compute
// bit-identical results. Clang 14 (the fuzz preset) cannot flatten a multiversioned
// function: there it is compiled once, for the baseline.
#ifdef __clang__
__attribute__((flatten))
#else
__attribute__((target_clones("arch=x86-64-v3", "default"), flatten))
#endif
void apply_stage(const Stage& stage, bool enters_lattice, const BatchView& v, std::size_t n) {
    double* __restrict px = v.x;
    double* __restrict py = v.y;
    double* __restrict ptx = v.tx;
    double* __restrict pty = v.ty;
    RayStatus* __restrict status = v.status;
    const double* __restrict axis_x = v.axis_x;
    const double* __restrict axis_y = v.axis_y;

    const RayMatrix m = stage.transfer;
    for (std::size_t k = 0; k < n; ++k) {
        const std::uint64_t alive = mask64(status[k] == RayStatus::Ok);
        const double x0 = px[k], y0 = py[k], tx0 = ptx[k], ty0 = pty[k];
        px[k] = select(alive, m.a * x0 + m.b * tx0, x0);
        py[k] = select(alive, m.a * y0 + m.b * ty0, y0);
        ptx[k] = select(alive, m.c * x0 + m.d * tx0, tx0);
        pty[k] = select(alive, m.c * y0 + m.d * ty0, ty0);
    }
    if (stage.lattice && enters_lattice) {
        if (stage.lattice->kind() == LatticeKind::Hexagonal)
            enter_lattice<LatticeKind::Hexagonal>(*stage.lattice, v, n);
        else
            enter_lattice<LatticeKind::Rectangular>(*stage.lattice, v, n);
    } else if (stage.lattice) {
        if (stage.lattice->kind() == LatticeKind::Hexagonal)
            stay_in_cell<LatticeKind::Hexagonal>(*stage.lattice, v, n);
        else
            stay_in_cell<LatticeKind::Rectangular>(*stage.lattice, v, n);
    } else if (stage.semi_diameter2 >= 0.0) {
        for (std::size_t k = 0; k < n; ++k) {
            const bool alive = status[k] == RayStatus::Ok;
            const bool outside = px[k] * px[k] + py[k] * py[k] > stage.semi_diameter2;
            status[k] = stop_if(alive, outside, RayStatus::Vignetted, status[k]);
        }
    }
    if (!stage.refracts) return;
    const double c = stage.refraction.c, d = stage.refraction.d;
    if (stage.lattice) {
        for (std::size_t k = 0; k < n; ++k) {
            const std::uint64_t alive = mask64(status[k] == RayStatus::Ok);
            ptx[k] = select(alive, c * (px[k] - axis_x[k]) + d * ptx[k], ptx[k]);
            pty[k] = select(alive, c * (py[k] - axis_y[k]) + d * pty[k], pty[k]);
        }
    } else {
        // Centred surfaces refract about h = 0; written as trace_prepared() does.
        for (std::size_t k = 0; k < n; ++k) {
            const std::uint64_t alive = mask64(status[k] == RayStatus::Ok);
            ptx[k] = select(alive, c * (px[k] - 0.0) + d * ptx[k], ptx[k]);
            pty[k] = select(alive, c * (py[k] - 0.0) + d * pty[k], pty[k]);
        }
    }
}

}  // namespace

void trace_paraxial_batch(const SequentialSystem& system, ParaxialBatch& batch, double z_start,
                          std::size_t first, std::size_t last) {
    const auto stages = prepare(system, z_start, first, last);
    constexpr std::size_t kBlock = 1024;  // rays per pass: the block stays in L1/L2
    parallel_for_chunks(batch.size(), 4096, [&](std::size_t begin, std::size_t end) {
        std::array<double, kBlock> axis_x, axis_y;
        for (std::size_t block = begin; block < end; block += kBlock) {
            const std::size_t n = std::min(kBlock, end - block);
            const BatchView view{batch.x.data() + block,      batch.y.data() + block,
                                 batch.tx.data() + block,     batch.ty.data() + block,
                                 batch.status.data() + block, batch.cell_i.data() + block,
                                 batch.cell_j.data() + block, axis_x.data(),
                                 axis_y.data()};
            std::fill_n(view.status, n, RayStatus::Ok);
            std::fill_n(view.cell_i, n, 0);
            std::fill_n(view.cell_j, n, 0);
            std::fill_n(view.axis_x, n, 0.0);
            std::fill_n(view.axis_y, n, 0.0);
            bool entered = false;
            for (const Stage& stage : stages) {
                apply_stage(stage, !entered, view, n);
                entered = entered || stage.lattice != nullptr;
            }
        }
    });
}

}  // namespace rfd::optics
