#include "optics/analysis.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.hpp"
#include "core/text.hpp"
#include "core/units.hpp"
#include "optics/spot.hpp"

namespace rfd::optics {
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
    auto add_image = [&](const char* key, const std::string& text, std::size_t plane_surface, std::size_t first,
                         std::size_t last, double object_z) {
        ConjugateCheck check;
        check.key = key;
        check.description = text;
        check.plane_z = system.surfaces[plane_surface].z;
        double m = std::nan("");
        check.target_z = image_z(system, first, last, object_z, &m).value_or(std::nan(""));
        check.magnification = m;
        check.tolerance = focal_tolerance(first, last);
        checks.push_back(check);
    };
    auto add_focus = [&](const char* key, const std::string& text, std::size_t plane_surface, std::size_t first,
                         std::size_t last, bool rear) {
        ConjugateCheck check;
        check.key = key;
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
        add_focus("pattern-focus", "pattern " + b + " in the back focal plane of " + a, enc, 0, enc - 1, true);
        if (design.kind == DesignKind::II) {
            const Plane* c = design.diffuser_plane();
            add_image("diffuser-image", "diffuser " + c->name + " = image of " + a + " through " + b,
                      system.find(c->name + " diffuser"), enc - 1, enc + 1, system.surfaces.front().z);
        }
        return checks;
    }
    // Designs III/IV: A main lens, B field lens, C meso-pixel lenslets, D pattern pair,
    // E projection lenslets.
    const std::size_t d_pattern = system.find(design.pattern_plane().name + " pattern");
    add_focus("meso-focus", "meso-pixel lenslets at the focus of the main lens (through the field lens)",
              enc, 0, enc - 1, true);
    add_image("pattern-image", "pattern = image of the main lens through field lens and meso lenslets", d_pattern,
              2, enc + 1, system.surfaces.front().z);
    if (d_pattern + 2 < system.surfaces.size()) {
        const std::size_t e_front = d_pattern + 2;
        add_image("projection-image", "projection lenslets = image of the meso lenslets through the pattern pair",
                  e_front, d_pattern - 1, d_pattern + 1, system.surfaces[enc].z);
        if (e_front + 1 < system.surfaces.size())
            add_focus("pattern-focal", "pattern in the front focal plane of the projection lenslets", d_pattern,
                      e_front, e_front + 1, false);
    }
    return checks;
}

}  // namespace

DesignSummary summarise(const DesignOptics& optics) {
    const Design& design = optics.design();
    const Lattice& lattice = optics.lattice();
    const SequentialSystem& system = optics.system();
    const bool variant = is_observer_variant(design.kind);
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

}  // namespace rfd::optics
