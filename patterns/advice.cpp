#include "patterns/advice.hpp"

#include <algorithm>
#include <filesystem>
#include <cmath>
#include <memory>

#include "core/error.hpp"
#include "core/text.hpp"
#include "optics/design.hpp"
#include "relight/interpolation.hpp"

namespace rfd::patterns {
namespace {

// The display incident direction whose chief ray lands `offset` from the axis on the
// encoding plane, paraxially: offset = B (tan x, tan y).
Eigen::Vector3d paraxial_direction(const optics::DesignOptics& optics, const Eigen::Vector2d& offset) {
    const Eigen::Vector2d slopes = offset / optics.paraxial_b();
    return Eigen::Vector3d(slopes.x(), slopes.y(), 1.0).normalized();
}

// Offsets the pattern's directions land at, over the range: one cell's probes for Designs
// I/II (every lenslet holds the whole range), the meso array's rim and middle for III/IV
// (each incident bin is one meso lenslet).
std::vector<Eigen::Vector2d> range_offsets(const optics::DesignOptics& optics) {
    const optics::Lattice& lattice = optics.lattice();
    if (!optics::is_observer_variant(optics.design().kind)) return optics::probe_offsets(lattice);
    const Eigen::Vector2d half = lattice.half_extent();
    std::vector<Eigen::Vector2d> offsets;
    constexpr int kSide = 8;
    for (int i = 0; i <= kSide; ++i) {
        const double t = -1.0 + 2.0 * i / kSide;
        offsets.emplace_back(t * half.x(), -half.y());
        offsets.emplace_back(t * half.x(), half.y());
        offsets.emplace_back(-half.x(), t * half.y());
        offsets.emplace_back(half.x(), t * half.y());
    }
    offsets.emplace_back(0.0, 0.0);
    return offsets;
}

// Whether a display direction lands inside the range: the centre cell (I/II), the meso
// array (III/IV).
bool lands_inside(const optics::DesignOptics& optics, const Eigen::Vector3d& display) {
    if (!(display.z() > 0.0)) return false;
    const Eigen::Vector2d offset = optics.paraxial_b() * Eigen::Vector2d(display.x() / display.z(), display.y() / display.z());
    const optics::Lattice& lattice = optics.lattice();
    if (optics::is_observer_variant(optics.design().kind)) {
        const Eigen::Vector2d half = lattice.half_extent();
        return std::abs(offset.x()) <= half.x() && std::abs(offset.y()) <= half.y();
    }
    const auto centre = optics.centre_cell();
    return lattice.cell_contains(centre, lattice.center(centre) + offset);
}

LightsInRange count_in_range(const optics::DesignOptics& optics, const std::vector<Eigen::Vector3d>& field_directions,
                             const relight::SphericalInterpolator* hull, const std::vector<Eigen::Vector2d>& offsets,
                             const AngularMapping& mapping) {
    LightsInRange out;
    out.total = static_cast<int>(field_directions.size());
    for (const Eigen::Vector3d& d : field_directions)
        if (lands_inside(optics, mapping.display_direction(d))) ++out.inside;
    out.covered = hull != nullptr;
    for (std::size_t k = 0; k < offsets.size() && out.covered; ++k)
        out.covered = hull->covers(mapping.field_direction(paraxial_direction(optics, offsets[k])));
    return out;
}

// The field's hull, or none when its lights are too few or too flat to span one.
std::unique_ptr<relight::SphericalInterpolator> hull_of(const std::vector<Eigen::Vector3d>& directions) {
    if (directions.size() < 3) return nullptr;
    try {
        return std::make_unique<relight::SphericalInterpolator>(directions);
    } catch (const Error&) {
        return nullptr;
    }
}

TiltChoice best_tilt_with(const optics::DesignOptics& optics, const std::vector<Eigen::Vector3d>& field_directions,
                          const relight::SphericalInterpolator* hull, AngularMapping mapping) {
    const std::vector<Eigen::Vector2d> offsets = range_offsets(optics);
    TiltChoice best;
    bool found = false;
    // From 0 outward, so that of equals the smallest tilt (the positive one first) wins.
    for (int step = 0; step <= 180; ++step) {
        const int tilt = step % 2 == 1 ? (step + 1) / 2 : -(step / 2);
        if (tilt < -90 || tilt > 90) continue;
        mapping.tilt_deg = tilt;
        const LightsInRange lights = count_in_range(optics, field_directions, hull, offsets, mapping);
        const bool better = !found || (lights.covered && !best.lights.covered) ||
                            (lights.covered == best.lights.covered && lights.inside > best.lights.inside);
        if (better) {
            best = {double(tilt), lights};
            found = true;
        }
    }
    return best;
}

std::string elements_text(const DesignFit& fit) {
    if (fit.kind == "III") return "one picture element (a single macro-pixel: angular output only)";
    return format_text("%d x %d picture elements (%s)", fit.elements_x, fit.elements_y,
                       fit.kind == "IV" ? "macro-pixels" : "one per lenslet");
}

std::string lights_text(const TiltChoice& choice) {
    return format_text("Lights inside the display's range at tilt %g deg: %d of the field's %d%s", choice.tilt_deg,
                       choice.lights.inside, choice.lights.total,
                       choice.lights.covered ? "" : " (and the lights do not surround the range: the pattern extrapolates)");
}

}  // namespace

std::optional<double> parse_tilt(const std::string& text, const std::string& option) {
    if (text == "auto") return std::nullopt;
    std::size_t used = 0;
    double value = 0.0;
    try {
        value = std::stod(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used == 0 || used != text.size() || !(value >= kTiltOption.min && value <= kTiltOption.max))
        throw InputError(option + ": '" + text + "': expected degrees from " + format_number(kTiltOption.min) + " to " +
                         format_number(kTiltOption.max) + ", or auto");
    return value;
}

LightsInRange lights_in_range(const optics::DesignOptics& optics, const std::vector<Eigen::Vector3d>& field_directions,
                              const AngularMapping& mapping) {
    const auto hull = hull_of(field_directions);
    return count_in_range(optics, field_directions, hull.get(), range_offsets(optics), mapping);
}

TiltChoice best_tilt(const optics::DesignOptics& optics, const std::vector<Eigen::Vector3d>& field_directions,
                     AngularMapping mapping) {
    const auto hull = hull_of(field_directions);
    return best_tilt_with(optics, field_directions, hull.get(), mapping);
}

DesignFit fit_design(const optics::Design& design, const std::string& file, int field_width, int field_height,
                     const std::vector<Eigen::Vector3d>& field_directions, const AngularMapping& mapping) {
    const optics::DesignOptics optics(design);
    DesignFit fit;
    fit.name = design.name;
    fit.file = file;
    fit.kind = std::string(optics::to_string(design.kind));
    fit.encodes_pictures = !optics::is_observer_variant(design.kind);
    if (design.kind == optics::DesignKind::III) {
        fit.elements_x = fit.elements_y = 1;
    } else if (design.kind == optics::DesignKind::IV && design.macro) {
        fit.elements_x = design.macro->count_x;
        fit.elements_y = design.macro->count_y;
    } else {
        fit.elements_x = optics.lattice().count_x();
        fit.elements_y = optics.lattice().count_y();
    }
    const auto hull = hull_of(field_directions);
    const std::vector<Eigen::Vector2d> offsets = range_offsets(optics);
    fit.at_given = {mapping.tilt_deg, count_in_range(optics, field_directions, hull.get(), offsets, mapping)};
    fit.at_best = best_tilt_with(optics, field_directions, hull.get(), mapping);
    if (fit.encodes_pictures && fit.at_best.lights.covered && fit.at_best.lights.inside >= 3)
        fit.shown_elements = static_cast<long long>(std::min(fit.elements_x, field_width)) *
                             std::min(fit.elements_y, field_height);
    return fit;
}

Advice advise(const optics::Design& chosen, const std::string& chosen_file, const std::vector<std::string>& bundled,
              const std::string& field_name, int field_width, int field_height,
              const std::vector<Eigen::Vector3d>& field_directions, const AngularMapping& mapping) {
    Advice a;
    a.field = field_name;
    a.field_width = field_width;
    a.field_height = field_height;
    a.lights = static_cast<int>(field_directions.size());
    a.chosen = fit_design(chosen, chosen_file, field_width, field_height, field_directions, mapping);
    for (const std::string& file : bundled)
        a.bundled.push_back(fit_design(optics::load_design(file), file, field_width, field_height, field_directions, mapping));
    for (std::size_t k = 0; k < a.bundled.size(); ++k) {
        const DesignFit& f = a.bundled[k];
        if (f.shown_elements == 0) continue;
        const bool better = a.best < 0 || f.shown_elements > a.bundled[static_cast<std::size_t>(a.best)].shown_elements ||
                            (f.shown_elements == a.bundled[static_cast<std::size_t>(a.best)].shown_elements &&
                             f.at_best.lights.inside > a.bundled[static_cast<std::size_t>(a.best)].at_best.lights.inside);
        if (better) a.best = static_cast<int>(k);
    }

    const DesignFit& c = a.chosen;
    const std::string field_size = format_text("%d x %d pixels", field_width, field_height);
    if (!c.encodes_pictures) {
        a.lines.push_back(c.name + " shows " + elements_text(c) + "; it takes angular fields (pattern encode-angular), "
                          "not a picture of " + field_size + ".");
    } else {
        const double per_x = double(field_width) / c.elements_x, per_y = double(field_height) / c.elements_y;
        a.lines.push_back(c.name + " shows " + elements_text(c) + "; the field has " + field_size +
                          (per_x >= 1.0 && per_y >= 1.0
                               ? format_text(": each element shows the mean of about %.0f x %.0f of them.", per_x, per_y)
                               : ": fewer than the display has elements, so neighbouring elements repeat pixels."));
    }
    a.lines.push_back(format_text("%s.", lights_text(c.at_given).c_str()));
    if (c.at_best.tilt_deg != c.at_given.tilt_deg &&
        (c.at_best.lights.inside != c.at_given.lights.inside || c.at_best.lights.covered != c.at_given.lights.covered))
        a.lines.push_back(format_text("tilt_deg = \"auto\" chooses %g deg: %d of %d lights inside%s.", c.at_best.tilt_deg,
                                      c.at_best.lights.inside, c.at_best.lights.total,
                                      c.at_best.lights.covered ? ", the range surrounded" : ""));
    if (a.best < 0) {
        a.lines.push_back("No bundled design shows this field with at least 3 of its lights inside a range they "
                          "surround: capture more lights around the directions the display shows.");
    } else {
        const DesignFit& b = a.bundled[static_cast<std::size_t>(a.best)];
        std::string others;
        for (const DesignFit& f : a.bundled)
            if (&f != &b && f.encodes_pictures)
                others += format_text("%s%s: %d x %d, %d lights", others.empty() ? "" : "; ",
                                      std::filesystem::path(f.file).stem().string().c_str(), f.elements_x, f.elements_y,
                                      f.at_best.lights.inside);
        const bool same = b.name == c.name && b.elements_x == c.elements_x && b.elements_y == c.elements_y;
        a.lines.push_back(
            std::string(same ? "Of the bundled designs this one shows the field best: "
                             : "Of the bundled designs " + std::filesystem::path(b.file).stem().string() + " (" +
                                   b.name + ") shows it best: ") +
            format_text("%d x %d picture elements of the field's %s, %d of its lights inside at tilt %g deg", b.elements_x,
                        b.elements_y, field_size.c_str(), b.at_best.lights.inside, b.at_best.tilt_deg) +
            (others.empty() ? "." : " (" + others + ")."));
    }
    return a;
}

}  // namespace rfd::patterns
