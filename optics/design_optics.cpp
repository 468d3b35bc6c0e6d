#include "optics/design_optics.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

#include "core/error.hpp"
#include "optics/paraxial.hpp"
#include "optics/spot.hpp"

namespace rfd::optics {

Eigen::Vector3d incident_direction(double theta, double phi) {
    return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

DesignOptics::DesignOptics(const Design& design) : design_(design), system_(build_system(design)) {
    const auto& surfaces = system_.surfaces;
    bool found_array = false;
    for (std::size_t s = 0; s < surfaces.size(); ++s) {
        if (std::holds_alternative<LatticeAperture>(surfaces[s].aperture)) {
            first_arrayed_ = s;
            found_array = true;
            break;
        }
    }
    if (!found_array)
        throw InputError(SourceLocation{design.file}, "the design has no lenslet array");
    if (is_observer_variant(design.kind)) {
        // Designs III/IV: the main lens turns direction into position on the meso-pixel
        // lenslets, the first arrayed surface.
        encoding_surface_ = first_arrayed_;
    } else {
        encoding_surface_ = system_.find(design.pattern_plane().name + " pattern");
    }
    entry_z_ = surfaces.front().z;
    paraxial_b_ = vertex_matrix(system_, 0, encoding_surface_).b;
    RFD_CHECK_MSG(std::abs(paraxial_b_) > 1e-12, "direction must map to position");
}

const Lattice& DesignOptics::lattice() const {
    return std::get<LatticeAperture>(system_.surfaces[first_arrayed_].aperture).lattice;
}

Eigen::Vector2d DesignOptics::dot_mm() const {
    return {design_.printer.dpi_x.dot_mm(), design_.printer.dpi_y.dot_mm()};
}

CellIndex DesignOptics::centre_cell() const { return lattice().cell_at(Eigen::Vector2d::Zero()); }

Ray DesignOptics::chief_ray(const Eigen::Vector3d& direction, CellIndex cell) const {
    // I/II: through the vertex of the entry lenslet. III/IV: through the main lens centre.
    const Eigen::Vector2d centre =
        is_observer_variant(design_.kind) ? Eigen::Vector2d::Zero() : lattice().center(cell);
    const Eigen::Vector3d through(centre.x(), centre.y(), entry_z_);
    return Ray{through - (1.0 / direction.z()) * direction, direction};
}

DesignOptics::Landing DesignOptics::land(const Eigen::Vector3d& direction, CellIndex cell,
                                         Model model) const {
    Landing landing;
    const Eigen::Vector2d reference =
        is_observer_variant(design_.kind) ? Eigen::Vector2d::Zero() : lattice().center(cell);
    if (model == Model::Paraxial) {
        const Ray ray = chief_ray(direction, cell);
        const ParaxialRay start{reference.x(), reference.y(), direction.x() / direction.z(),
                                direction.y() / direction.z()};
        const ParaxialResult result =
            trace_paraxial(system_, start, entry_z_, 0, encoding_surface_);
        (void)ray;
        landing.offset = Eigen::Vector2d(result.ray.x, result.ray.y) - reference;
        landing.status = result.status;
        landing.surface = result.surface;
        landing.cell = lattice().cell_at({result.ray.x, result.ray.y});
        return landing;
    }
    const TraceResult result = trace(system_, chief_ray(direction, cell), 0, encoding_surface_);
    landing.offset = result.ray.origin.head<2>() - reference;
    landing.status = result.status;
    landing.surface = result.surface;
    landing.cell = lattice().cell_at(result.ray.origin.head<2>());
    return landing;
}

std::optional<Eigen::Vector3d> DesignOptics::direction_for(const Eigen::Vector2d& offset,
                                                           CellIndex cell, Model model) const {
    Eigen::Vector2d slopes = offset / paraxial_b_;
    auto direction_of = [](const Eigen::Vector2d& s) {
        return Eigen::Vector3d(s.x(), s.y(), 1.0).normalized();
    };
    if (model == Model::Paraxial) return direction_of(slopes);
    // Newton on the exact forward map, with a finite-difference Jacobian.
    constexpr double kStep = 1e-7;
    for (int iteration = 0; iteration < 40; ++iteration) {
        const Landing at = land(direction_of(slopes), cell, Model::Exact);
        if (at.status != RayStatus::Ok) return std::nullopt;
        const Eigen::Vector2d residual = at.offset - offset;
        if (residual.norm() < 1e-9) return direction_of(slopes);
        Eigen::Matrix2d jacobian;
        for (int k = 0; k < 2; ++k) {
            Eigen::Vector2d shifted = slopes;
            shifted[k] += kStep;
            const Landing moved = land(direction_of(shifted), cell, Model::Exact);
            if (moved.status != RayStatus::Ok) return std::nullopt;
            jacobian.col(k) = (moved.offset - at.offset) / kStep;
        }
        if (std::abs(jacobian.determinant()) < 1e-18) return std::nullopt;
        slopes -= jacobian.inverse() * residual;
        if (!slopes.allFinite()) return std::nullopt;
    }
    return std::nullopt;
}

DesignOptics::BundleReport DesignOptics::trace_bundle(const Eigen::Vector3d& direction,
                                                      CellIndex cell, int rays_per_side) const {
    BundleReport report;
    report.lost_per_surface.assign(system_.surfaces.size(), {});
    const bool variant = is_observer_variant(design_.kind);
    // The entry aperture: the lenslet cell (I/II) or the main lens disc (III/IV).
    double half = 0.0;
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    double disc = 0.0;
    if (variant) {
        disc = std::get<CircularAperture>(system_.surfaces.front().aperture).semi_diameter;
        half = disc;
    } else {
        centre = lattice().center(cell);
        half = lattice().circumradius();
    }
    std::vector<Eigen::Vector2d> landed;
    const std::size_t last = system_.surfaces.size() - 1;
    for (int iy = 0; iy < rays_per_side; ++iy) {
        for (int ix = 0; ix < rays_per_side; ++ix) {
            const double fx = (ix + 0.5) / rays_per_side * 2.0 - 1.0;
            const double fy = (iy + 0.5) / rays_per_side * 2.0 - 1.0;
            const Eigen::Vector2d point = centre + half * Eigen::Vector2d(fx, fy);
            const bool inside = variant ? (point - centre).norm() <= disc
                                        : lattice().cell_contains(cell, point);
            if (!inside) continue;
            const Eigen::Vector3d through(point.x(), point.y(), entry_z_);
            // Start far enough in front of the vertex plane to clear any sag.
            const Ray ray{through - (2.0 / direction.z()) * direction, direction};
            ++report.rays;
            const TraceResult full = trace(system_, ray, 0, last);
            if (full.status == RayStatus::Ok) {
                ++report.arrived;
                report.transmitted += full.transmittance;
            } else {
                ++report.lost_per_surface[static_cast<std::size_t>(full.surface)]
                                         [static_cast<std::size_t>(full.status)];
                if (full.status == RayStatus::CrossedCell) ++report.crossed;
            }
            const TraceResult at_encoding = trace(system_, ray, 0, encoding_surface_);
            if (at_encoding.status == RayStatus::Ok)
                landed.push_back(at_encoding.ray.origin.head<2>());
        }
    }
    report.rms_spot_radius = spot_statistics(landed).rms_radius;
    return report;
}

bool DesignOptics::bundle_crosses(const Eigen::Vector3d& direction, CellIndex cell,
                                  int rays_per_side) const {
    RFD_CHECK(rays_per_side >= 2);
    const bool variant = is_observer_variant(design_.kind);
    const Surface& entry = system_.surfaces.front();
    // The entry aperture: the lenslet cell (I/II) or the main lens disc (III/IV), as a
    // polygon of corners relative to its centre (a disc as a polygon of 8 x rays_per_side).
    const Eigen::Vector2d centre = variant ? Eigen::Vector2d::Zero() : lattice().center(cell);
    std::vector<Eigen::Vector2d> corners;
    if (variant) {
        const double disc = std::get<CircularAperture>(entry.aperture).semi_diameter;
        const int sides = 8 * rays_per_side;
        for (int k = 0; k < sides; ++k)
            corners.push_back(disc * Eigen::Vector2d(std::cos(2 * kPi * k / sides), std::sin(2 * kPi * k / sides)));
    } else {
        corners = lattice().cell_corners();
    }
    std::vector<Eigen::Vector2d> points;
    for (std::size_t k = 0; k < corners.size(); ++k) {
        const Eigen::Vector2d& a = corners[k];
        const Eigen::Vector2d& b = corners[(k + 1) % corners.size()];
        const int along = variant ? 1 : rays_per_side;
        for (int m = 0; m < along; ++m) points.push_back(a + (b - a) * (double(m) / along));
    }
    Eigen::Vector2d low = corners.front(), high = corners.front();
    for (const auto& c : corners) {
        low = low.cwiseMin(c);
        high = high.cwiseMax(c);
    }
    for (int iy = 0; iy < rays_per_side; ++iy) {
        for (int ix = 0; ix < rays_per_side; ++ix) {
            const Eigen::Vector2d f(double(ix) / (rays_per_side - 1), double(iy) / (rays_per_side - 1));
            const Eigen::Vector2d p = low + f.cwiseProduct(high - low);
            const bool inside = variant ? p.squaredNorm() <= corners.front().squaredNorm()
                                        : lattice().cell_contains(cell, centre + p);
            if (inside) points.push_back(p);
        }
    }
    const std::size_t last = system_.surfaces.size() - 1;
    for (const Eigen::Vector2d& p : points) {
        // A hair inside the rim, so that the ray aimed at this lenslet's edge meets it and
        // not its neighbour's; aimed at the entry surface itself, whose edge lies deeper
        // than its vertex by the sag.
        const Eigen::Vector2d q = (1.0 - 1e-9) * p;
        const double z = entry.z + sag(entry.profile, q.squaredNorm()).value_or(0.0);
        const Eigen::Vector3d at(centre.x() + q.x(), centre.y() + q.y(), z);
        const double back = z - (std::min(entry.z, z) - 2.0);
        const Ray ray{at - (back / direction.z()) * direction, direction};
        if (trace(system_, ray, 0, last).status == RayStatus::CrossedCell) return true;
    }
    return false;
}

}  // namespace rfd::optics
