#include "optics/meso_pixel.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"

namespace rfd::optics {

std::string_view to_string(DotLight light) {
    switch (light) {
        case DotLight::Lit: return "lit";
        case DotLight::Unlit: return "unlit";
        case DotLight::Crossed: return "crossed";
        case DotLight::Lost: return "lost";
    }
    return "?";
}

namespace {

Eigen::Vector3d from_slopes(double tx, double ty) { return Eigen::Vector3d(tx, ty, 1.0).normalized(); }

// Exact rays start this far (mm, along z) in front of C's vertex: clear of its sag, and
// behind the field lens, which ends 0.5 mm before C in the presets.
constexpr double kLeadIn = 0.25;

}  // namespace

MesoPixelOptics::MesoPixelOptics(const DesignOptics& optics)
    : optics_(optics), backward_(reversed(optics.system())) {
    const Design& design = optics.design();
    const SourceLocation where{design.file, 0, 0, "design.kind"};
    if (design.kind != DesignKind::III && design.kind != DesignKind::IV)
        throw InputError(where, "angular (meso-pixel) optics need a Design III or IV, got Design " +
                                    std::string(to_string(design.kind)));
    const SequentialSystem& system = optics.system();
    c_front_ = optics.encoding_surface();
    d_pattern_ = system.find(design.pattern_plane().name + " pattern");
    last_ = system.surfaces.size() - 1;
    const bool arrayed_after = [&] {
        for (std::size_t s = d_pattern_ + 1; s <= last_; ++s)
            if (std::holds_alternative<LatticeAperture>(system.surfaces[s].aperture)) return true;
        return false;
    }();
    if (c_front_ == 0 || d_pattern_ <= c_front_ || !arrayed_after)
        throw InputError(where, "Designs III/IV need a main lens, meso-pixel lenslets, the pattern "
                                "behind them and projection lenslets behind the pattern");
    cd_ = vertex_matrix(system, c_front_, d_pattern_);
    de_ = vertex_matrix(system, d_pattern_, last_);
    RFD_CHECK_MSG(std::abs(cd_.b) > 1e-12, "C must map slope to position on D");
    gain_ = de_.c + de_.d * cd_.d / cd_.b;
    const double per_mm = std::abs(de_.d * (cd_.c - cd_.d * cd_.a / cd_.b));
    spread_ = per_mm * 0.5 * Eigen::Vector2d(lattice().pitch_x(), lattice().pitch_y());
}

std::optional<Eigen::Vector2d> MesoPixelOptics::chief_slope(const Eigen::Vector2d& offset,
                                                            CellIndex cell, Model model) const {
    Eigen::Vector2d slope = offset / cd_.b;
    if (model == Model::Paraxial) return slope;
    const SequentialSystem& system = optics_.system();
    const Eigen::Vector2d h = lattice().center(cell);
    const double z_c = system.surfaces[c_front_].z;
    auto landing = [&](const Eigen::Vector2d& s) -> std::optional<Eigen::Vector2d> {
        const Eigen::Vector3d d = from_slopes(s.x(), s.y());
        const Ray ray{Eigen::Vector3d(h.x(), h.y(), z_c) - (kLeadIn / d.z()) * d, d};
        const TraceResult r = trace(system, ray, c_front_, d_pattern_);
        if (r.status != RayStatus::Ok) return std::nullopt;
        return Eigen::Vector2d(r.ray.origin.head<2>() - h);
    };
    constexpr double kStep = 1e-7;
    for (int iteration = 0; iteration < 30; ++iteration) {
        const auto at = landing(slope);
        if (!at) return std::nullopt;
        const Eigen::Vector2d residual = *at - offset;
        if (residual.norm() < 1e-10) return slope;
        Eigen::Matrix2d jacobian;
        for (int k = 0; k < 2; ++k) {
            Eigen::Vector2d shifted = slope;
            shifted[k] += kStep;
            const auto moved = landing(shifted);
            if (!moved) return std::nullopt;
            jacobian.col(k) = (*moved - *at) / kStep;
        }
        if (std::abs(jacobian.determinant()) < 1e-18) return std::nullopt;
        slope -= jacobian.inverse() * residual;
        if (!slope.allFinite()) return std::nullopt;
    }
    return std::nullopt;
}

DotRay MesoPixelOptics::follow(const Eigen::Vector2d& slope, CellIndex cell, Model model) const {
    const SequentialSystem& system = optics_.system();
    const Eigen::Vector2d h = lattice().center(cell);
    const double z_c = system.surfaces[c_front_].z;
    // Backward from C_k's vertex through B and A: the reversed system mirrors z only.
    const std::size_t n = system.surfaces.size();
    const std::size_t back_first = n - c_front_, back_last = n - 1;
    DotRay out;
    RayStatus back_status = RayStatus::Ok, forward_status = RayStatus::Ok;
    int back_surface = -1, forward_surface = -1;
    if (model == Model::Paraxial) {
        const ParaxialResult back = trace_paraxial(backward_, {h.x(), h.y(), -slope.x(), -slope.y()},
                                                   -z_c, back_first, back_last);
        back_status = back.status;
        back_surface = static_cast<int>(n - 1) - back.surface;
        out.incident = from_slopes(-back.ray.tx, -back.ray.ty);
        const ParaxialResult forward =
            trace_paraxial(system, {h.x(), h.y(), slope.x(), slope.y()}, z_c, c_front_, last_);
        forward_status = forward.status;
        forward_surface = forward.surface;
        out.output = from_slopes(forward.ray.tx, forward.ray.ty);
    } else {
        const Eigen::Vector3d d = from_slopes(slope.x(), slope.y());
        const Eigen::Vector3d vertex(h.x(), h.y(), z_c);
        const TraceResult back = trace(backward_, Ray{Eigen::Vector3d(h.x(), h.y(), -z_c),
                                                      Eigen::Vector3d(-d.x(), -d.y(), d.z())},
                                       back_first, back_last);
        back_status = back.status;
        back_surface = static_cast<int>(n - 1) - back.surface;
        const Eigen::Vector3d& r = back.ray.direction;
        out.incident = Eigen::Vector3d(-r.x(), -r.y(), r.z()).normalized();
        const TraceResult forward =
            trace(system, Ray{vertex - (kLeadIn / d.z()) * d, d}, c_front_, last_);
        forward_status = forward.status;
        forward_surface = forward.surface;
        out.output = forward.ray.direction.normalized();
    }
    if (back_status != RayStatus::Ok) {
        // A or B stop it: the dot lies outside the image of the main lens, nothing lights it.
        out.light = back_status == RayStatus::Vignetted ? DotLight::Unlit : DotLight::Lost;
        out.status = back_status;
        out.surface = back_surface;
    } else if (forward_status != RayStatus::Ok) {
        out.light = forward_status == RayStatus::CrossedCell ? DotLight::Crossed : DotLight::Lost;
        out.status = forward_status;
        out.surface = forward_surface;
    } else {
        out.light = DotLight::Lit;
    }
    return out;
}

DotRay MesoPixelOptics::dot(const Eigen::Vector2d& offset, CellIndex cell, Model model) const {
    const auto slope = chief_slope(offset, cell, model);
    if (!slope) {
        DotRay lost;
        lost.light = DotLight::Lost;
        lost.status = RayStatus::Missed;
        lost.surface = static_cast<int>(d_pattern_);
        return lost;
    }
    return follow(*slope, cell, model);
}

std::optional<Eigen::Vector2d> MesoPixelOptics::offset_for(const Eigen::Vector3d& output,
                                                           CellIndex cell, Model model) const {
    if (!(output.z() > 0.0)) return std::nullopt;
    const Eigen::Vector2d target(output.x() / output.z(), output.y() / output.z());
    Eigen::Vector2d offset = target / gain_;
    if (model == Model::Paraxial) return offset;
    auto slopes_at = [&](const Eigen::Vector2d& p) -> std::optional<Eigen::Vector2d> {
        const auto s = chief_slope(p, cell, Model::Exact);
        if (!s) return std::nullopt;
        const Eigen::Vector3d d = from_slopes(s->x(), s->y());
        const Eigen::Vector2d h = lattice().center(cell);
        const double z_c = optics_.system().surfaces[c_front_].z;
        const TraceResult r = trace(optics_.system(),
                                    Ray{Eigen::Vector3d(h.x(), h.y(), z_c) - (kLeadIn / d.z()) * d, d},
                                    c_front_, last_);
        if (r.status != RayStatus::Ok && r.status != RayStatus::CrossedCell) return std::nullopt;
        const Eigen::Vector3d& o = r.ray.direction;
        return Eigen::Vector2d(o.x() / o.z(), o.y() / o.z());
    };
    constexpr double kStep = 1e-6;
    for (int iteration = 0; iteration < 30; ++iteration) {
        const auto at = slopes_at(offset);
        if (!at) return std::nullopt;
        const Eigen::Vector2d residual = *at - target;
        if (residual.norm() < 1e-11) return offset;
        Eigen::Matrix2d jacobian;
        for (int k = 0; k < 2; ++k) {
            Eigen::Vector2d shifted = offset;
            shifted[k] += kStep;
            const auto moved = slopes_at(shifted);
            if (!moved) return std::nullopt;
            jacobian.col(k) = (*moved - *at) / kStep;
        }
        if (std::abs(jacobian.determinant()) < 1e-18) return std::nullopt;
        offset -= jacobian.inverse() * residual;
        if (!offset.allFinite()) return std::nullopt;
    }
    return std::nullopt;
}

IncidentBin MesoPixelOptics::bin(CellIndex cell, Model model, int samples_per_side) const {
    RFD_CHECK(samples_per_side >= 1);
    IncidentBin bin;
    bin.cell = cell;
    const Lattice& l = lattice();
    const Eigen::Vector2d centre = l.center(cell);
    // DesignOptics maps absolute positions on C for Designs III/IV (chief rays through the
    // main lens's centre).
    // The paraxial map always exists; the exact one may not converge far off axis.
    auto centre_direction = optics_.direction_for(centre, cell, model);
    if (!centre_direction) centre_direction = optics_.direction_for(centre, cell, Model::Paraxial);
    bin.centre = *centre_direction;
    Eigen::Vector2d half = Eigen::Vector2d::Zero();
    for (const auto& corner : l.cell_corners()) half = half.cwiseMax(corner.cwiseAbs());
    for (int iy = 0; iy < samples_per_side; ++iy)
        for (int ix = 0; ix < samples_per_side; ++ix) {
            const Eigen::Vector2d fraction((ix + 0.5) / samples_per_side - 0.5,
                                           (iy + 0.5) / samples_per_side - 0.5);
            const Eigen::Vector2d point = centre + 2.0 * fraction.cwiseProduct(half);
            if (!l.cell_contains(cell, point)) continue;
            if (const auto d = optics_.direction_for(point, cell, model)) bin.samples.push_back(*d);
        }
    // Mean over the two opposite edges that the model can map (the field lens vignettes the
    // outer edge of the corner bins).
    auto half_width = [&](const Eigen::Vector2d& unit) {
        double sum = 0.0;
        int count = 0;
        for (const double sign : {-1.0, 1.0}) {
            // A hair inside the edge: on the array's outer edge the exact map stops.
            const Eigen::Vector2d edge = centre + sign * (1.0 - 1e-9) * l.boundary_distance(unit) * unit;
            if (const auto d = optics_.direction_for(edge, cell, model)) {
                sum += radians_to_degrees(angle_between(*d, bin.centre));
                ++count;
            }
        }
        return count > 0 ? sum / count : 0.0;
    };
    bin.half_width_x_deg = half_width(Eigen::Vector2d::UnitX());
    bin.half_width_y_deg = half_width(Eigen::Vector2d::UnitY());
    return bin;
}

}  // namespace rfd::optics
