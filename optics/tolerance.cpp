#include "optics/tolerance.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "core/error.hpp"
#include "core/progress.hpp"
#include "optics/misalignment.hpp"

namespace rfd::optics {

std::string_view to_string(MountingError kind) {
    switch (kind) {
        case MountingError::Shift: return "shift";
        case MountingError::Rotation: return "rotation";
        case MountingError::PitchError: return "pitch_error";
        case MountingError::Spacer: return "spacer";
    }
    return "?";
}

namespace {

// Largest distance of a lenslet centre from the array's axis, mm.
double largest_centre_radius(const Lattice& lattice) {
    double radius = 0.0;
    for (int j = 0; j < lattice.count_y(); ++j)
        for (int i = 0; i < lattice.count_x(); ++i) radius = std::max(radius, lattice.center({i, j}).norm());
    return radius;
}

void check_range(double value, const std::string& what) {
    if (!std::isfinite(value) || value < 0.0)
        throw InputError(SourceLocation{"", 0, 0, what}, "expected a finite number >= 0, got " + std::to_string(value));
}

// The pictures the display shows under each light on its own.
struct Pictures {
    std::vector<Image> lenslets;             // per_lenslet(), one per light
    std::vector<Eigen::Vector2d> centroids;  // mm on the diffuser; NaN when the picture is black
};

Eigen::Vector2d centroid(const DiffuserImage& out) {
    double total = 0.0;
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    for (int y = 0; y < out.image.height(); ++y)
        for (int x = 0; x < out.image.width(); ++x) {
            double w = 0.0;
            for (int c = 0; c < out.image.channels(); ++c) w += out.image.at(x, y, c);
            total += w;
            sum += w * out.pixel_centre(x, y);
        }
    if (!(total > 0.0)) return Eigen::Vector2d::Constant(std::nan(""));
    return sum / total;
}

Pictures simulate_each(const DisplaySimulator& simulator, const Transparency& pattern,
                       const std::vector<DisplayLight>& lights, const SimulationOptions& options, Progress& progress) {
    Pictures pictures;
    for (const DisplayLight& light : lights) {
        const DiffuserImage out = simulator.simulate(pattern, {light}, options);
        pictures.lenslets.push_back(simulator.per_lenslet(out));
        pictures.centroids.push_back(centroid(out));
        progress.advance();
    }
    return pictures;
}

// Mean over the lights of the centroid's displacement, in lenslet pitches (lights whose
// picture is black in either are skipped).
double mean_shift(const Pictures& nominal, const Pictures& changed, double pitch) {
    double sum = 0.0;
    int count = 0;
    for (std::size_t k = 0; k < nominal.centroids.size(); ++k) {
        const Eigen::Vector2d d = changed.centroids[k] - nominal.centroids[k];
        if (!d.allFinite()) continue;
        sum += d.norm();
        ++count;
    }
    return count ? sum / count / pitch : 0.0;
}

}  // namespace

double stacked_psnr(const std::vector<Image>& nominal, const std::vector<Image>& pictures) {
    RFD_CHECK(nominal.size() == pictures.size());
    double peak = 0.0, squared = 0.0;
    std::size_t samples = 0;
    // Fixed order (light, then sample): the same sum every run.
    for (std::size_t k = 0; k < nominal.size(); ++k) {
        RFD_CHECK(nominal[k].same_shape(pictures[k]));
        const auto a = nominal[k].samples();
        const auto b = pictures[k].samples();
        for (std::size_t s = 0; s < a.size(); ++s) {
            peak = std::max(peak, static_cast<double>(a[s]));
            const double d = static_cast<double>(a[s]) - static_cast<double>(b[s]);
            squared += d * d;
        }
        samples += a.size();
    }
    if (samples == 0 || !(peak > 0.0)) return 0.0;
    const double mse = squared / static_cast<double>(samples);
    if (!(mse > 0.0)) return kPsnrCeilingDb;
    return std::min(kPsnrCeilingDb, 10.0 * std::log10(peak * peak / mse));
}

ToleranceOptions default_tolerance_ranges(const DesignOptics& optics) {
    const Lattice& lattice = optics.lattice();
    const double pitch = std::min(lattice.pitch_x(), lattice.pitch_y());
    const double radius = std::max(largest_centre_radius(lattice), pitch);
    ToleranceOptions options;
    options.max_shift_mm = pitch / 2.0;
    options.max_rotation_rad = std::atan(pitch / 2.0 / radius);
    options.max_pitch_error = pitch / 2.0 / radius;
    options.max_spacer_mm = pattern_to_diffuser_mm(optics.design()) / 4.0;
    return options;
}

std::vector<DisplayLight> default_tolerance_lights(const DesignOptics& optics, Model model) {
    double wrap_deg = 89.0;
    for (double phi : {0.0, std::numbers::pi / 2})
        if (const auto angle = wrap_over_angle(optics, phi, model)) wrap_deg = std::min(wrap_deg, *angle);
    const double theta = wrap_deg / 2.0 * std::numbers::pi / 180.0;
    std::vector<DisplayLight> lights(1);
    for (int k = 0; k < 2; ++k) {
        DisplayLight light;
        light.direction = incident_direction(theta, k * std::numbers::pi / 2);
        lights.push_back(light);
    }
    return lights;
}

ToleranceReport sweep_tolerances(const Design& design, const Transparency& pattern,
                                 const std::vector<DisplayLight>& lights, const ToleranceOptions& options) {
    check_range(options.max_shift_mm, "largest shift (mm)");
    check_range(options.max_rotation_rad, "largest rotation");
    check_range(options.max_pitch_error, "largest pitch error");
    check_range(options.max_spacer_mm, "largest spacer error (mm)");
    if (options.max_pitch_error >= 0.5)
        throw InputError(SourceLocation{"", 0, 0, "largest pitch error"},
                         "expected a relative error below 50 %, got " + std::to_string(100 * options.max_pitch_error) + " %");
    if (options.steps < 1)
        throw InputError(SourceLocation{"", 0, 0, "steps"}, "expected at least 1, got " + std::to_string(options.steps));
    if (options.refinements < 0)
        throw InputError(SourceLocation{"", 0, 0, "refinements"}, "expected 0 or more");
    if (!std::isfinite(options.threshold_db) || options.threshold_db >= kPsnrCeilingDb)
        throw InputError(SourceLocation{"", 0, 0, "threshold (dB)"},
                         "expected a finite number below " + std::to_string(kPsnrCeilingDb) + " dB");
    if (lights.empty()) throw InputError(SourceLocation{"", 0, 0, "lights"}, "expected at least one light");

    std::vector<std::pair<MountingError, double>> kinds;
    if (options.max_shift_mm > 0) kinds.emplace_back(MountingError::Shift, options.max_shift_mm);
    if (options.max_rotation_rad > 0) kinds.emplace_back(MountingError::Rotation, options.max_rotation_rad);
    if (options.max_pitch_error > 0) kinds.emplace_back(MountingError::PitchError, options.max_pitch_error);
    if (options.max_spacer_mm > 0) kinds.emplace_back(MountingError::Spacer, options.max_spacer_mm);
    if (kinds.empty())
        throw InputError(SourceLocation{"", 0, 0, "ranges"}, "every range is zero: nothing to sweep");
    // Refuse an impossible spacer before any simulation runs.
    if (options.max_spacer_mm > 0) (void)with_spacer_error(design, -options.max_spacer_mm);

    const DisplaySimulator nominal_simulator(design);
    const double pitch = nominal_simulator.optics().lattice().pitch_x();
    const std::size_t trials = kinds.size() * 2 * static_cast<std::size_t>(options.steps + options.refinements);
    Progress progress("tolerance sweep", (1 + trials) * lights.size());
    const Pictures nominal = simulate_each(nominal_simulator, pattern, lights, options.simulation, progress);

    ToleranceReport report;
    for (const Image& picture : nominal.lenslets)
        for (float v : picture.samples()) report.nominal_peak = std::max(report.nominal_peak, static_cast<double>(v));
    if (!(report.nominal_peak > 0.0))
        throw InputError(SourceLocation{"", 0, 0, "lights"},
                         "the display shows a black picture under these lights: nothing to compare");

    // The worse of +value and -value.
    auto trial = [&](MountingError kind, double value) {
        TolerancePoint point{value, kPsnrCeilingDb, 0.0};
        if (value == 0.0) return point;
        for (double sign : {1.0, -1.0}) {
            Pictures pictures;
            if (kind == MountingError::Spacer) {
                const DisplaySimulator simulator(with_spacer_error(design, sign * value));
                pictures = simulate_each(simulator, pattern, lights, options.simulation, progress);
            } else {
                Mounting mounting;
                if (kind == MountingError::Shift) mounting.shift_mm = {sign * value, 0.0};
                if (kind == MountingError::Rotation) mounting.rotation_rad = sign * value;
                if (kind == MountingError::PitchError) mounting.pitch_error = sign * value;
                const MisalignedTransparency mounted(pattern, mounting);
                pictures = simulate_each(nominal_simulator, mounted, lights, options.simulation, progress);
            }
            point.psnr_db = std::min(point.psnr_db, stacked_psnr(nominal.lenslets, pictures.lenslets));
            point.shift_lenslets = std::max(point.shift_lenslets, mean_shift(nominal, pictures, pitch));
        }
        return point;
    };

    for (const auto& [kind, largest] : kinds) {
        ToleranceCurve curve;
        curve.kind = kind;
        std::optional<std::size_t> first_below;
        for (int k = 0; k <= options.steps; ++k) {
            curve.sweep.push_back(trial(kind, largest * k / options.steps));
            if (!first_below && curve.sweep.back().psnr_db < options.threshold_db) first_below = curve.sweep.size() - 1;
        }
        if (first_below) {
            // Bisection on the first bracket [above, below] of the sweep.
            double above = curve.sweep[*first_below - 1].error;
            double below = curve.sweep[*first_below].error;
            for (int r = 0; r < options.refinements; ++r) {
                const double middle = 0.5 * (above + below);
                curve.refinement.push_back(trial(kind, middle));
                (curve.refinement.back().psnr_db >= options.threshold_db ? above : below) = middle;
            }
            curve.tolerance = above;
        }
        report.curves.push_back(std::move(curve));
    }
    progress.finish();
    return report;
}

}  // namespace rfd::optics
