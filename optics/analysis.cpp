#include "optics/analysis.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <sstream>

#include "core/error.hpp"
#include "core/units.hpp"
#include "optics/spot.hpp"
#include "core/text.hpp"

namespace rfd::optics {

Eigen::Vector3d incident_direction(double theta, double phi) {
    return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

namespace {

bool is_observer_variant(const Design& design) {
    return design.kind == DesignKind::III || design.kind == DesignKind::IV;
}

}  // namespace

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
    if (is_observer_variant(design)) {
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
        is_observer_variant(design_) ? Eigen::Vector2d::Zero() : lattice().center(cell);
    const Eigen::Vector3d through(centre.x(), centre.y(), entry_z_);
    return Ray{through - (1.0 / direction.z()) * direction, direction};
}

DesignOptics::Landing DesignOptics::land(const Eigen::Vector3d& direction, CellIndex cell,
                                         Model model) const {
    Landing landing;
    const Eigen::Vector2d reference =
        is_observer_variant(design_) ? Eigen::Vector2d::Zero() : lattice().center(cell);
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
    const bool variant = is_observer_variant(design_);
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
    const bool variant = is_observer_variant(design_);
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

namespace {

// First angle in (0, 89] degrees along phi where `fails` holds, assuming it holds from
// there on; nullopt if it never does.
template <typename Predicate>
std::optional<double> first_failure(Predicate fails) {
    constexpr double kStep = 0.25;
    double ok = 0.0;
    if (fails(0.0)) return 0.0;
    for (double angle = kStep; angle <= kWrapOverSearchLimitDeg + 1e-9; angle += kStep) {
        if (!fails(angle)) {
            ok = angle;
            continue;
        }
        double lo = ok, hi = angle;
        for (int i = 0; i < 40; ++i) {
            const double mid = 0.5 * (lo + hi);
            (fails(mid) ? hi : lo) = mid;
        }
        return 0.5 * (lo + hi);
    }
    return std::nullopt;
}

}  // namespace

std::optional<double> wrap_over_angle(const DesignOptics& optics, double phi, Model model) {
    const CellIndex cell = optics.centre_cell();
    return first_failure([&](double angle_deg) {
        const auto d = incident_direction(degrees_to_radians(angle_deg), phi);
        return optics.land(d, cell, model).status != RayStatus::Ok;
    });
}

std::optional<double> first_loss_angle(const DesignOptics& optics, double phi, int rays_per_side) {
    const CellIndex cell = optics.centre_cell();
    return first_failure([&](double angle_deg) {
        return optics.bundle_crosses(incident_direction(degrees_to_radians(angle_deg), phi), cell,
                                     rays_per_side);
    });
}

std::vector<SweepDirection> sweep_directions(const Lattice& lattice) {
    if (lattice.kind() == LatticeKind::Hexagonal)
        return {{"flat (x)", "x", 0.0}, {"corner (y)", "y", kPi / 2}};
    return {{"x", "x", 0.0}, {"y", "y", kPi / 2}, {"diagonal", "diagonal", std::atan2(lattice.pitch_y(), lattice.pitch_x())}};
}

namespace {

const PlanoConvex* entry_lens(const Design& design) {
    const Plane& first = design.planes.front();
    if (!first.part) return nullptr;
    if (const auto* lens = std::get_if<LensPart>(&*first.part)) return &lens->lens;
    if (const auto* array = std::get_if<LensletArrayPart>(&*first.part)) return &array->lens;
    return nullptr;
}

}  // namespace

std::optional<double> image_z(const SequentialSystem& system, std::size_t first,
                              std::size_t last, double object_z, double* magnification) {
    const CardinalPoints points = cardinal_points(system, first, last);
    const auto image = conjugate(points, system.surfaces[first].z - object_z);
    if (!image) return std::nullopt;
    if (magnification) *magnification = image->magnification;
    return system.surfaces[last].z + image->image_distance;
}

namespace {

// The planes each design needs in focus or conjugate (thesis figures 8.5, 8.8, 8.11).
std::vector<ConjugateCheck> conjugate_checks(const DesignOptics& optics) {
    const Design& design = optics.design();
    const SequentialSystem& system = optics.system();
    const std::size_t enc = optics.encoding_surface();
    std::vector<ConjugateCheck> checks;
    auto focal_tolerance = [&](std::size_t first, std::size_t last) {
        return 0.02 * std::abs(cardinal_points(system, first, last).efl);
    };
    auto add_image = [&](const std::string& text, std::size_t plane_surface, std::size_t first,
                         std::size_t last, double object_z) {
        ConjugateCheck check;
        check.description = text;
        check.plane_z = system.surfaces[plane_surface].z;
        double m = std::nan("");
        check.target_z = image_z(system, first, last, object_z, &m).value_or(std::nan(""));
        check.magnification = m;
        check.tolerance = focal_tolerance(first, last);
        checks.push_back(check);
    };
    auto add_focus = [&](const std::string& text, std::size_t plane_surface, std::size_t first,
                         std::size_t last, bool rear) {
        ConjugateCheck check;
        check.description = text;
        check.plane_z = system.surfaces[plane_surface].z;
        const CardinalPoints points = cardinal_points(system, first, last);
        check.target_z = rear ? points.rear_focal_z : points.front_focal_z;
        check.tolerance = focal_tolerance(first, last);
        checks.push_back(check);
    };
    const std::string a = design.planes.front().name;
    if (design.kind == DesignKind::I || design.kind == DesignKind::II) {
        const std::string b = design.pattern_plane().name;
        add_focus("pattern " + b + " in the back focal plane of " + a, enc, 0, enc - 1, true);
        if (design.kind == DesignKind::II) {
            const Plane* c = design.diffuser_plane();
            add_image("diffuser " + c->name + " = image of " + a + " through " + b,
                      system.find(c->name + " diffuser"), enc - 1, enc + 1, system.surfaces.front().z);
        }
        return checks;
    }
    // Designs III/IV: A main lens, B field lens, C meso-pixel lenslets, D pattern pair,
    // E projection lenslets.
    const std::size_t d_pattern = system.find(design.pattern_plane().name + " pattern");
    add_focus("meso-pixel lenslets at the focus of the main lens (through the field lens)",
              enc, 0, enc - 1, true);
    add_image("pattern = image of the main lens through field lens and meso lenslets", d_pattern,
              2, enc + 1, system.surfaces.front().z);
    if (d_pattern + 2 < system.surfaces.size()) {
        const std::size_t e_front = d_pattern + 2;
        add_image("projection lenslets = image of the meso lenslets through the pattern pair",
                  e_front, d_pattern - 1, d_pattern + 1, system.surfaces[enc].z);
        if (e_front + 1 < system.surfaces.size())
            add_focus("pattern in the front focal plane of the projection lenslets", d_pattern,
                      e_front, e_front + 1, false);
    }
    return checks;
}

}  // namespace

DesignSummary summarise(const DesignOptics& optics) {
    const Design& design = optics.design();
    const Lattice& lattice = optics.lattice();
    const SequentialSystem& system = optics.system();
    const bool variant = is_observer_variant(design);
    DesignSummary s;
    s.name = design.name;
    s.kind = std::string(to_string(design.kind));
    s.lattice = lattice.kind() == LatticeKind::Hexagonal ? "hexagonal" : "rectangular";
    s.pitch_x = lattice.pitch_x();
    s.pitch_y = lattice.pitch_y();
    s.count_x = lattice.count_x();
    s.count_y = lattice.count_y();
    s.macro = design.macro;
    if (const PlanoConvex* lens = entry_lens(design)) s.focal_length_nominal = lens->nominal_focal_length;
    s.focal_length_paraxial = cardinal_points(system, 0, 1).efl;
    s.dpi_x = design.printer.dpi_x.value;
    s.dpi_y = design.printer.dpi_y.value;
    const Eigen::Vector2d dot = optics.dot_mm();
    s.directions_per_lenslet = lattice.cell_area() / (dot.x() * dot.y());
    const double b = std::abs(optics.paraxial_b());
    if (variant) {
        // One incident-direction bin per meso-pixel lenslet.
        s.angular_step_x_deg = radians_to_degrees(std::atan(lattice.pitch_x() / b));
        s.angular_step_y_deg = radians_to_degrees(std::atan(lattice.pitch_y() / b));
    } else {
        s.angular_step_x_deg = radians_to_degrees(std::atan(dot.x() / b));
        s.angular_step_y_deg = radians_to_degrees(std::atan(dot.y() / b));
    }
    std::optional<double> min_wrap;
    for (const auto& sweep : sweep_directions(lattice)) {
        const auto paraxial = wrap_over_angle(optics, sweep.phi, Model::Paraxial);
        const auto exact = wrap_over_angle(optics, sweep.phi, Model::Exact);
        s.wrap_over_paraxial_deg.emplace_back(sweep.name, paraxial);
        s.wrap_over_exact_deg.emplace_back(sweep.name, exact);
        if (exact) min_wrap = std::min(min_wrap.value_or(*exact), *exact);
        if (!variant) s.crosstalk_exact_deg.emplace_back(sweep.name, first_loss_angle(optics, sweep.phi, 15));
    }
    if (min_wrap) s.field_of_view_deg = 2.0 * *min_wrap;
    // "Half the field of view": half of the smallest wrap-over angle, or of the search's
    // limit when no direction wraps over.
    const double reach_deg = min_wrap.value_or(kWrapOverSearchLimitDeg);
    const CellIndex cell = optics.centre_cell();
    const auto on_axis = optics.trace_bundle(incident_direction(0, 0), cell, 41);
    const auto half_fov = optics.trace_bundle(
        incident_direction(degrees_to_radians(0.5 * reach_deg), 0), cell, 41);
    s.efficiency_on_axis = on_axis.rays ? double(on_axis.arrived) / double(on_axis.rays) : 0.0;
    s.efficiency_at_half_fov = half_fov.rays ? double(half_fov.arrived) / double(half_fov.rays) : 0.0;
    s.efficiency_fresnel_on_axis = on_axis.rays ? on_axis.transmitted / double(on_axis.rays) : 0.0;
    s.efficiency_fresnel_at_half_fov = half_fov.rays ? half_fov.transmitted / double(half_fov.rays) : 0.0;
    for (const auto& [angle, report] : {std::pair{0.0, &on_axis}, std::pair{0.5 * reach_deg, &half_fov}}) {
        for (std::size_t k = 0; k < report->lost_per_surface.size(); ++k)
            for (int status = 1; status < kRayStatusCount; ++status) {
                const std::size_t n = report->lost_per_surface[k][static_cast<std::size_t>(status)];
                if (n > 0)
                    s.losses.push_back({angle, system.surfaces[k].label, static_cast<RayStatus>(status),
                                        double(n) / double(report->rays)});
            }
    }
    s.spot_rms_on_axis_um = 1000.0 * on_axis.rms_spot_radius;
    s.spot_rms_at_half_fov_um = 1000.0 * half_fov.rms_spot_radius;

    const std::size_t enc = optics.encoding_surface();
    const CardinalPoints before = cardinal_points(system, 0, enc - 1);
    s.focus_error_mm = system.surfaces[enc].z - before.rear_focal_z;

    // Design rules.
    const double aperture = variant ? 2.0 * std::get<CircularAperture>(system.surfaces.front().aperture).semi_diameter
                                    : std::min(lattice.pitch_x(), lattice.pitch_y());
    const double blur = aperture * std::abs(s.focus_error_mm) / std::abs(before.rear_focal_length);
    const double smallest_feature = variant ? std::min(lattice.pitch_x(), lattice.pitch_y()) / 4
                                            : std::min(dot.x(), dot.y());
    if (blur > smallest_feature)
        s.warnings.push_back("the encoding plane lies " + format_fixed(s.focus_error_mm, 4) +
                             " mm from the paraxial focus: defocus blur " + format_fixed(1000 * blur, 1) +
                             " um exceeds " + format_fixed(1000 * smallest_feature, 1) + " um");
    for (const auto* report : {&on_axis, &half_fov}) {
        std::size_t tir = 0;
        for (std::size_t k = 0; k < report->lost_per_surface.size(); ++k) {
            const std::size_t n = report->lost_per_surface[k][static_cast<std::size_t>(RayStatus::TotalInternalReflection)];
            if (n == 0) continue;
            tir += n;
            s.warnings.push_back(
                format_fixed(100.0 * double(n) / double(report->rays), 1) + "% of the rays " +
                (report == &on_axis ? "on axis" : "at half the field of view") +
                " are lost to total internal reflection at '" + system.surfaces[k].label +
                "'" + (k % 2 == 1 ? " (a flat-side-first lens: turn its curved side toward the light)" : ""));
        }
        (void)tir;
    }
    if (!variant && s.directions_per_lenslet < 64)
        s.warnings.push_back("only " + format_fixed(s.directions_per_lenslet, 0) +
                             " print pixels per lenslet: the angular resolution is coarse");
    if (min_wrap && *min_wrap < 5.0)
        s.warnings.push_back("wrap-over begins at " + format_fixed(*min_wrap, 2) +
                             " deg: the display's field of view is very narrow");
    s.conjugates = conjugate_checks(optics);
    for (const auto& check : s.conjugates) {
        const double miss = check.plane_z - check.target_z;
        if (!std::isfinite(check.target_z))
            s.warnings.push_back(check.description + ": the image is at infinity");
        else if (std::abs(miss) > check.tolerance)
            s.warnings.push_back(check.description + ": the plane is " + format_fixed(miss, 3) +
                                 " mm from where the optics put it (z = " +
                                 format_fixed(check.target_z, 3) + " mm)");
        if (std::isfinite(check.magnification) && design.kind == DesignKind::II &&
            std::abs(std::abs(check.magnification) - 1.0) > 0.1)
            s.warnings.push_back("plane B images each lenslet of A onto the diffuser at " +
                                 format_fixed(std::abs(check.magnification), 3) + "x: macro-pixels " +
                                 (std::abs(check.magnification) > 1 ? "overlap" : "leave gaps"));
    }
    return s;
}

Chart accuracy_chart(const DesignOptics& optics, double phi, const std::string& name,
                     double max_angle_deg, int steps) {
    Chart chart;
    chart.direction = name;
    const Eigen::Vector2d along(std::cos(phi), std::sin(phi));
    const Eigen::Vector2d dot = optics.dot_mm();
    const double pixel = std::hypot(along.x() * dot.x(), along.y() * dot.y());
    const CellIndex cell = optics.centre_cell();
    for (int k = 0; k <= steps; ++k) {
        ChartRow row;
        row.angle_deg = max_angle_deg * k / steps;
        const auto d = incident_direction(degrees_to_radians(row.angle_deg), phi);
        const auto paraxial = optics.land(d, cell, Model::Paraxial);
        const auto exact = optics.land(d, cell, Model::Exact);
        row.exact_status = exact.status;
        // Both models must reach the encoding plane (landing there under a neighbouring
        // lenslet counts: that is where wrap-over shows); a ray stopped earlier has no
        // position on it to compare.
        const auto reached = [&](const DesignOptics::Landing& l) {
            return l.surface == static_cast<int>(optics.encoding_surface()) &&
                   (l.status == RayStatus::Ok || l.status == RayStatus::CrossedCell);
        };
        const bool arrived = reached(exact) && reached(paraxial);
        row.paraxial_mm = reached(paraxial) ? paraxial.offset.dot(along) : std::nan("");
        row.exact_mm = arrived ? exact.offset.dot(along) : std::nan("");
        row.error_um = arrived ? 1000.0 * (row.exact_mm - row.paraxial_mm) : std::nan("");
        row.error_pixels = arrived ? (row.exact_mm - row.paraxial_mm) / pixel : std::nan("");
        if (!chart.half_pixel_angle_deg && arrived && std::abs(row.error_pixels) > 0.5)
            chart.half_pixel_angle_deg = row.angle_deg;
        chart.rows.push_back(row);
    }
    return chart;
}

double measure_rays_per_second(const DesignOptics& optics, Model model, std::size_t rays,
                               double max_angle_deg) {
    const SequentialSystem& system = optics.system();
    const Eigen::Vector2d half = optics.lattice().half_extent();
    const double z0 = system.surfaces.front().z - 2.0;
    const double max_slope = std::tan(degrees_to_radians(max_angle_deg));
    std::mt19937_64 random(12345);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    const std::size_t last = optics.encoding_surface();
    using Clock = std::chrono::steady_clock;
    if (model == Model::Exact) {
        RayBatch batch;
        batch.resize(rays);
        for (std::size_t k = 0; k < rays; ++k) {
            const Eigen::Vector3d d =
                Eigen::Vector3d(max_slope * unit(random), max_slope * unit(random), 1.0).normalized();
            batch.set(k, Ray{Eigen::Vector3d(half.x() * unit(random), half.y() * unit(random), z0), d});
        }
        const auto start = Clock::now();
        trace_batch(system, batch, 0, last);
        const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
        return static_cast<double>(rays) / std::max(seconds, 1e-9);
    }
    ParaxialBatch batch;
    batch.resize(rays);
    for (std::size_t k = 0; k < rays; ++k) {
        batch.x[k] = half.x() * unit(random);
        batch.y[k] = half.y() * unit(random);
        batch.tx[k] = max_slope * unit(random);
        batch.ty[k] = max_slope * unit(random);
    }
    const auto start = Clock::now();
    trace_paraxial_batch(system, batch, z0, 0, last);
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    return static_cast<double>(rays) / std::max(seconds, 1e-9);
}

}  // namespace rfd::optics
