#include "predict/compare.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/error.hpp"
#include "core/text.hpp"
#include "patterns/raster.hpp"
#include "core/progress.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "predict/optimize.hpp"

namespace rfd::predict {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

double psnr_of(double peak, double mse) {
    if (mse <= 0.0) return std::numeric_limits<double>::infinity();
    if (peak <= 0.0) return 0.0;
    return 10.0 * std::log10(peak * peak / mse);
}

}  // namespace

MacroPixelCore macro_pixel_core(const optics::DesignOptics& optics) {
    MacroPixelCore core;
    if (optics.design().kind != optics::DesignKind::II) return core;
    // The corrective pair's imaging of A onto the diffuser: the one conjugate check of a
    // Design II with a magnification (the others are focal-plane checks).
    for (const optics::ConjugateCheck& check : optics::summarise(optics).conjugates)
        if (std::isfinite(check.magnification) && std::abs(check.magnification) > 1.0) {
            core.magnification = std::abs(check.magnification);
            core.fraction = std::clamp(2.0 - core.magnification, 0.25, 1.0);
        }
    return core;
}

Image per_lenslet_core(const optics::Lattice& lattice, const optics::DiffuserImage& image, double fraction) {
    return optics::per_lenslet(lattice, image, fraction);
}

ImageComparison compare_images(const Image& prediction, const Image& reference) {
    RFD_CHECK(prediction.same_shape(reference));
    ImageComparison out;
    out.error = Image(reference.width(), reference.height(), reference.channels());
    const auto p = prediction.samples(), q = reference.samples();
    auto e = out.error.samples();
    double sum = 0.0, pq = 0.0, pp = 0.0;
    for (std::size_t k = 0; k < q.size(); ++k) {
        const double diff = static_cast<double>(p[k]) - static_cast<double>(q[k]);
        e[k] = static_cast<float>(diff);
        sum += diff * diff;
        pq += static_cast<double>(p[k]) * q[k];
        pp += static_cast<double>(p[k]) * p[k];
        out.peak = std::max(out.peak, static_cast<double>(q[k]));
    }
    const double n = static_cast<double>(std::max<std::size_t>(q.size(), 1));
    out.mse = sum / n;
    out.psnr_db = psnr_of(out.peak, out.mse);
    out.fitted_gain = pp > 0.0 ? pq / pp : 1.0;
    double fitted = 0.0;
    for (std::size_t k = 0; k < q.size(); ++k) {
        const double diff = out.fitted_gain * p[k] - q[k];
        fitted += diff * diff;
    }
    out.fitted_mse = fitted / n;
    out.psnr_fitted_db = psnr_of(out.peak, out.fitted_mse);
    return out;
}

EncodedField::EncodedField(const optics::Design& design, const std::string& pattern_file,
                           const patterns::PatternGeometry& geometry, double pattern_white,
                           const std::string& field_path) {
    const patterns::PatternFileInfo info = patterns::read_pattern_info(pattern_file);
    patterns::EncodeOptions options = patterns::encode_options_of(info, pattern_file);
    options.field_name = field_path;
    field_ = patterns::load_field_for(design, field_path, options);
    if (field_.channels() != info.channels)
        throw InputError(SourceLocation{field_path},
                         "the field has " + std::to_string(field_.channels()) + " channel(s), the pattern '" +
                             pattern_file + "' " + std::to_string(info.channels) + ": not the field it was encoded from");
    encoder_ = std::make_unique<patterns::Encoder>(design, field_, geometry, options);
    // The pattern records the white its encoder found; the same field and options find the
    // same one, another field almost never does.
    if (std::abs(encoder_->white() - pattern_white) > 1e-3 * pattern_white)
        throw InputError(SourceLocation{field_path},
                         "not the field the pattern '" + pattern_file + "' was encoded from: its white is " +
                             format_number(encoder_->white()) + ", the pattern's rfd:white " +
                             format_number(pattern_white) + " (pattern field '" +
                             (info.attributes.count("field") ? info.attributes.at("field") : "?") + "')");
}

DisplayComparison::DisplayComparison(const optics::DisplaySimulator& simulator, const optics::Transparency& pattern,
                                     const patterns::Encoder& encoder, const print::ToneMap& tone)
    : simulator_(simulator), pattern_(pattern), encoder_(encoder), tone_(tone) {
    RFD_CHECK(tone.brightness > 0.0 && tone.white > 0.0 && (tone.sheets == 1 || tone.sheets == 2));
    const optics::Lattice& a = simulator.optics().lattice();
    const optics::Lattice& b = encoder.lattice();
    RFD_CHECK(a.count_x() == b.count_x() && a.count_y() == b.count_y());
    core_ = macro_pixel_core(simulator.optics());
}

Image DisplayComparison::transmittance(const Eigen::Vector3d& field_direction) const {
    const Eigen::Vector3d d = encoder_.options().mapping.display_direction(field_direction.normalized());
    const optics::Lattice& lattice = encoder_.lattice();
    Image out(lattice.count_x(), lattice.count_y(), 3);
    if (!(d.z() > 0.0)) return out;  // no light reaches the display from there
    // t' = b + (1 - b) u: the black level on the desired transmittance.
    const std::vector<double> u = desired_transmittance(encoder_, tone_, d);
    const double black = tone_.stack_transmittance(0.0);
    for (int j = 0; j < lattice.count_y(); ++j)
        for (int i = 0; i < lattice.count_x(); ++i)
            for (int c = 0; c < 3; ++c)
                out.at(i, lattice.count_y() - 1 - j, c) = static_cast<float>(
                    black + (1.0 - black) * u[lattice.linear_index({i, j}) * 3 + static_cast<std::size_t>(c)]);
    return out;
}

bool DisplayComparison::inside_field_of_view(const Eigen::Vector3d& display_direction) const {
    const optics::DesignOptics& optics = simulator_.optics();
    const optics::CellIndex centre = optics.centre_cell();
    const optics::DesignOptics::Landing landing = optics.land(display_direction, centre, optics::Model::Exact);
    return landing.status == optics::RayStatus::Ok && landing.cell == centre;
}

bool DisplayComparison::crosstalk_free(const Eigen::Vector3d& display_direction) const {
    const optics::DesignOptics& optics = simulator_.optics();
    const optics::DesignOptics::BundleReport bundle = optics.trace_bundle(display_direction, optics.centre_cell(), 16);
    return bundle.arrived > 0 && bundle.crossed == 0;
}

DirectionComparison DisplayComparison::compare(const Eigen::Vector3d& field_direction,
                                               const optics::SimulationOptions& options) const {
    const auto start = Clock::now();
    DirectionComparison out;
    out.field_direction = field_direction.normalized();
    out.display_direction = encoder_.options().mapping.display_direction(out.field_direction);
    if (!(out.display_direction.z() > 1e-6)) {
        const SphericalAngles a = angles_of(out.field_direction);
        throw InputError("a light from field theta " + std::to_string(radians_to_degrees(a.theta)) + ", phi " +
                         std::to_string(radians_to_degrees(a.phi)) +
                         " deg reaches the display from the front, not through it from behind");
    }
    out.display_angle_deg = radians_to_degrees(std::acos(std::clamp(out.display_direction.z(), -1.0, 1.0)));
    out.inside_field_of_view = inside_field_of_view(out.display_direction);
    out.crosstalk_free = out.inside_field_of_view && crosstalk_free(out.display_direction);
    const optics::DisplayLight light{out.display_direction, {1.0, 1.0, 1.0}, 0.0};
    const optics::DiffuserImage diffuser = simulator_.simulate(pattern_, {light}, options);
    out.core = core_;
    out.efficiency = diffuser.optical_efficiency;
    out.rays = diffuser.rays;
    // The display's response to a clear print under the same light: the scale of Q.
    const optics::ClearTransparency clear;
    const optics::DiffuserImage flat = simulator_.simulate(clear, {light}, options);
    const Image transmitted = transmittance(out.field_direction);
    auto times = [&](Image response) {
        for (int c = 0; c < response.channels(); ++c)
            for (int y = 0; y < response.height(); ++y)
                for (int x = 0; x < response.width(); ++x) response.at(x, y, c) *= transmitted.at(x, y, c);
        return response;
    };
    out.cell_prediction = simulator_.per_lenslet(diffuser);
    out.cell_reference = times(simulator_.per_lenslet(flat));
    out.cell_comparison = compare_images(out.cell_prediction, out.cell_reference);
    if (core_.fraction < 1.0) {
        // The simulator splats bilinearly: a neighbour's light reaches one pixel into the core.
        const double sampled = std::max(0.1, core_.fraction - 2.0 / options.pixels_per_pitch);
        const optics::Lattice& lattice = simulator_.optics().lattice();
        out.prediction = per_lenslet_core(lattice, diffuser, sampled);
        out.reference = times(per_lenslet_core(lattice, flat, sampled));
        out.comparison = compare_images(out.prediction, out.reference);
    } else {
        out.prediction = out.cell_prediction;
        out.reference = out.cell_reference;
        out.comparison = out.cell_comparison;
    }
    out.seconds = seconds_since(start);
    return out;
}

std::vector<Eigen::Vector3d> DisplayComparison::sweep(int count) const {
    std::vector<Eigen::Vector3d> out;
    const double reach = encoder_.display_range().max_angle_rad;
    const double golden_angle = std::numbers::pi * (3.0 - std::sqrt(5.0));
    for (int k = 0; k < count; ++k) {
        const double angle = count > 1 ? reach * std::sqrt(static_cast<double>(k) / (count - 1)) : 0.0;
        const Eigen::Vector3d d = optics::incident_direction(angle, golden_angle * k);
        out.push_back(encoder_.options().mapping.field_direction(d).normalized());
    }
    return out;
}

Image side_by_side(const DirectionComparison& result, int pixels_per_lenslet, double error_gain) {
    RFD_CHECK(pixels_per_lenslet >= 1);
    const Image& p = result.prediction;
    const int w = p.width() * pixels_per_lenslet, h = p.height() * pixels_per_lenslet, gap = pixels_per_lenslet;
    Image out(3 * w + 2 * gap, h, 3, 0.5f);
    const double peak = result.comparison.peak > 0.0 ? result.comparison.peak : 1.0;
    auto draw = [&](int panel, auto value) {
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c)
                    out.at(panel * (w + gap) + x, y, c) =
                        static_cast<float>(value(x / pixels_per_lenslet, y / pixels_per_lenslet, c) / peak);
    };
    draw(0, [&](int x, int y, int c) { return static_cast<double>(result.prediction.at(x, y, c)); });
    draw(1, [&](int x, int y, int c) { return static_cast<double>(result.reference.at(x, y, c)); });
    draw(2, [&](int x, int y, int c) { return error_gain * std::abs(result.comparison.error.at(x, y, c)); });
    return out;
}

std::vector<AccuracyPoint> accuracy_sweep(const optics::DisplaySimulator& simulator,
                                          const optics::Transparency& pattern,
                                          const std::vector<Eigen::Vector3d>& display_directions,
                                          const std::vector<AccuracyModel>& models,
                                          const std::vector<int>& rays_per_side, int reference_rays,
                                          const optics::SimulationOptions& base) {
    RFD_CHECK(!display_directions.empty() && reference_rays >= 1);
    auto simulate = [&](const Eigen::Vector3d& d, optics::Model model, int rays, std::size_t* traced) {
        optics::SimulationOptions options = base;
        options.model = model;
        options.rays_per_side = rays;
        const optics::DiffuserImage image = simulator.simulate(pattern, {optics::DisplayLight{d, {1, 1, 1}, 0.0}}, options);
        if (traced) *traced += image.rays;
        return simulator.per_lenslet(image);
    };
    Progress progress("speed against accuracy", display_directions.size() * (1 + models.size() * rays_per_side.size()));
    std::vector<Image> converged;
    double peak = 0.0;
    for (const Eigen::Vector3d& d : display_directions) {
        converged.push_back(simulate(d, optics::Model::Exact, reference_rays, nullptr));
        progress.advance();
        for (float v : converged.back().samples()) peak = std::max(peak, static_cast<double>(v));
    }
    std::vector<AccuracyPoint> points;
    for (const AccuracyModel& model : models)
        for (int rays : rays_per_side) {
            AccuracyPoint point;
            point.label = model.label;
            point.rays_per_side = rays;
            point.worst_psnr_db = std::numeric_limits<double>::infinity();
            std::vector<Image> predictions;
            const auto start = Clock::now();
            for (const Eigen::Vector3d& d : display_directions) predictions.push_back(simulate(d, model.model, rays, &point.rays));
            point.seconds = seconds_since(start);
            progress.advance(display_directions.size());
            const double directions = static_cast<double>(predictions.size());
            for (std::size_t k = 0; k < predictions.size(); ++k) {
                const ImageComparison c = compare_images(predictions[k], converged[k]);
                point.mse += c.mse / directions;
                point.fitted_mse += c.fitted_mse / directions;
                point.psnr_per_direction_db.push_back(c.psnr_db);
                point.fitted_psnr_per_direction_db.push_back(c.psnr_fitted_db);
                point.worst_psnr_db = std::min(point.worst_psnr_db, c.psnr_db);
            }
            point.psnr_db = psnr_of(peak, point.mse);
            point.fitted_psnr_db = psnr_of(peak, point.fitted_mse);
            points.push_back(point);
        }
    return points;
}

}  // namespace rfd::predict
