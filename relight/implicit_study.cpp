#include "relight/implicit_study.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include "core/error.hpp"
#include "core/units.hpp"
#include "relight/render.hpp"
#include "relight/sampling.hpp"

namespace rfd::relight {
namespace {

// Uniform in [0, 1) from the top 53 bits: the same on every platform, unlike
// std::uniform_real_distribution.
double unit(std::mt19937_64& engine) { return static_cast<double>(engine() >> 11) * 0x1.0p-53; }

}  // namespace

std::vector<StageLight> implicit_training_lights(std::size_t count, std::uint64_t seed) {
    if (count < 1) throw InputError("implicit training lights: expected at least one light");
    constexpr double kRadiiDeg[] = {15.0, 25.0, 40.0};
    std::vector<StageLight> lights;
    std::size_t i = 0;
    for (const Eigen::Vector3d& d : repulsion_pattern(count, seed))
        lights.push_back({d, LightKernel::smooth(degrees_to_radians(kRadiiDeg[i++ % 3]))});
    return lights;
}

std::vector<StageLight> held_out_lights(std::size_t count, std::uint64_t seed, double min_elevation,
                                        double min_radius, double max_radius) {
    if (!(min_elevation >= 0.0 && min_elevation < std::numbers::pi / 2.0) ||
        !(min_radius > 0.0 && max_radius >= min_radius && max_radius < std::numbers::pi))
        throw InputError("held-out lights: expected 0 <= min elevation < 90 degrees and 0 < min radius <= "
                         "max radius < 180 degrees");
    std::mt19937_64 engine(seed);
    std::vector<StageLight> lights;
    const double z_max = 1.0, z_min = std::sin(min_elevation);
    for (std::size_t i = 0; i < count; ++i) {
        // Uniform over the spherical zone: z uniform (Archimedes), azimuth uniform.
        const double z = z_min + (z_max - z_min) * unit(engine);
        const double phi = 2.0 * std::numbers::pi * unit(engine);
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double radius = min_radius + (max_radius - min_radius) * unit(engine);
        lights.push_back({{r * std::cos(phi), r * std::sin(phi), z}, LightKernel::smooth(radius)});
    }
    return lights;
}

void add_camera_noise(Image& image, double sigma, std::uint64_t seed) {
    if (!(sigma >= 0.0 && std::isfinite(sigma)))
        throw InputError("camera noise: expected a standard deviation >= 0, got " + std::to_string(sigma));
    if (sigma == 0.0) return;
    std::mt19937_64 engine(seed);
    const std::span<float> samples = image.samples();
    for (std::size_t i = 0; i < samples.size(); i += 2) {
        // Box-Muller: two independent normals from two uniforms (1 - u keeps the log finite).
        const double radius = sigma * std::sqrt(-2.0 * std::log(1.0 - unit(engine)));
        const double angle = 2.0 * std::numbers::pi * unit(engine);
        samples[i] += static_cast<float>(radius * std::cos(angle));
        if (i + 1 < samples.size()) samples[i + 1] += static_cast<float>(radius * std::sin(angle));
    }
}

EtaStudy study_eta(const ImplicitModel& model, const std::vector<Image>& training_images,
                   const std::vector<Image>& test_probes, const std::vector<Image>& references,
                   const std::vector<double>& etas, bool second_pass) {
    if (training_images.size() != model.count)
        throw InputError("eta study: the model was trained on " + std::to_string(model.count) + " images, given " +
                         std::to_string(training_images.size()));
    if (test_probes.empty() || test_probes.size() != references.size())
        throw InputError("eta study: expected one reference image per test probe (at least one), given " +
                         std::to_string(test_probes.size()) + " probes and " + std::to_string(references.size()) +
                         " references");
    if (etas.empty()) throw InputError("eta study: no eta to study");
    for (const double eta : etas)
        if (!(eta >= 0.0 && std::isfinite(eta)))
            throw InputError("eta study: expected every eta >= 0, got " + std::to_string(eta));
    double peak = 0.0;
    std::size_t samples = 0;
    for (std::size_t t = 0; t < references.size(); ++t) {
        if (!references[t].same_shape(training_images.front()))
            throw InputError("eta study: reference " + std::to_string(t) +
                             " does not have the training images' size and channels");
        for (const float s : references[t].samples()) peak = std::max(peak, double(s));
        samples += references[t].samples().size();
    }
    if (!(peak > 0.0)) throw InputError("eta study: every reference image is black; PSNR is undefined");

    EtaStudy study;
    for (const double eta : etas) {
        EtaStudyPoint point;
        point.eta = eta;
        double total = 0.0, residual = 0.0;
        for (std::size_t t = 0; t < test_probes.size(); ++t) {
            const ImplicitFit fit = implicit_fit(model, test_probes[t], {.eta = eta, .second_pass = second_pass});
            const Image predicted = relight(training_images, fit.coefficients());
            const double mse = mean_squared_error(predicted, references[t]);
            total += mse * static_cast<double>(references[t].samples().size());
            point.light_psnr.push_back(psnr_from_mse(mse, peak));
            residual += fit.residual_rms * fit.residual_rms;
            point.max_abs_coefficient = std::max(point.max_abs_coefficient, fit.l.cwiseAbs().maxCoeff());
        }
        point.psnr = psnr_from_mse(total / static_cast<double>(samples), peak);
        point.probe_residual_rms = std::sqrt(residual / static_cast<double>(test_probes.size()));
        study.points.push_back(std::move(point));
    }
    for (std::size_t i = 1; i < study.points.size(); ++i)
        if (study.points[i].psnr > study.points[study.best].psnr) study.best = i;
    return study;
}

std::vector<double> default_eta_grid(const ImplicitModel& model) {
    double square = 0.0;
    Eigen::Index count = 0;
    for (const auto& channel : model.pca) {
        square += channel.mean.squaredNorm();
        count += channel.mean.size();
    }
    const double scale = count > 0 && square > 0.0 ? square / static_cast<double>(count) : 1.0;
    std::vector<double> etas{0.0};
    for (int k = -12; k <= 4; ++k) etas.push_back(scale * std::pow(10.0, 0.5 * k));
    return etas;
}

}  // namespace rfd::relight
