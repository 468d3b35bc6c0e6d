#include "relight/implicit_study.hpp"

#include <algorithm>
#include <cstdio>
#include <utility>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image_io.hpp"
#include "core/plot.hpp"
#include "core/progress.hpp"
#include "core/text.hpp"
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


namespace {

// The sample below which `fraction` of the image's samples lie: an exposure for viewing that
// a few highlight pixels do not decide.
float percentile(const Image& image, double fraction) {
    std::vector<float> samples(image.samples().begin(), image.samples().end());
    const auto k = static_cast<std::size_t>(fraction * static_cast<double>(samples.size() - 1));
    std::nth_element(samples.begin(), samples.begin() + static_cast<std::ptrdiff_t>(k), samples.end());
    return samples[k];
}

Image scaled(const Image& image, float factor) {
    Image out = image;
    for (float& s : out.samples()) s *= factor;
    return out;
}

// The pseudo-inverse's point (eta 0; the last if given twice), if there.
std::optional<std::size_t> pseudo_inverse_of(const EtaStudy& study) {
    std::optional<std::size_t> found;
    for (std::size_t i = 0; i < study.points.size(); ++i)
        if (!(study.points[i].eta > 0.0)) found = i;
    return found;
}

}  // namespace

std::vector<Image> read_training_images(const std::vector<std::filesystem::path>& files) {
    std::vector<Image> images;
    Progress progress("reading training images", files.size());
    for (const auto& file : files) {
        Image image = read_image(file);
        if (!images.empty() && !image.same_shape(images.front()))
            throw InputError(SourceLocation{file.string()},
                             "is " + std::to_string(image.width()) + " x " + std::to_string(image.height()) + " with " +
                                 std::to_string(image.channels()) + " channel(s); the first training image is " +
                                 std::to_string(images.front().width()) + " x " +
                                 std::to_string(images.front().height()) + " with " +
                                 std::to_string(images.front().channels()));
        images.push_back(std::move(image));
        progress.advance();
    }
    progress.finish();
    return images;
}

HeldOutSet read_held_out_set(const std::filesystem::path& folder, const ImplicitModelFiles& files,
                             const Image& training_shape, std::size_t examples) {
    const std::vector<std::filesystem::path> photo_files = field_image_files(folder / "photos");
    const std::vector<std::filesystem::path> truth_files = field_image_files(folder / "truth");
    if (photo_files.size() != truth_files.size())
        throw InputError(SourceLocation{folder.string()}, "photos/ lists " + std::to_string(photo_files.size()) +
                                                              " images and truth/ " + std::to_string(truth_files.size()));
    HeldOutSet set;
    for (std::size_t t = 0; t < photo_files.size(); ++t) {
        Image photo = read_image(photo_files[t]);
        Image truth = read_image(truth_files[t]);
        for (const auto& [file, image] : {std::pair{photo_files[t], &photo}, std::pair{truth_files[t], &truth}})
            if (!image->same_shape(training_shape))
                throw InputError(SourceLocation{file.string()}, "does not have the training images' size and channels");
        try {
            set.probes.push_back(crop_probe(photo, files.box, files.model.size));
        } catch (const InputError& e) {
            throw InputError(SourceLocation{photo_files[t].string()}, e.what());
        }
        set.truths.push_back(std::move(truth));
        if (t < examples) set.photos.push_back(std::move(photo));
    }
    return set;
}

bool write_eta_sweep_report(const std::filesystem::path& folder, const EtaStudy& study, const ImplicitModel& model,
                            const std::vector<Image>& training, const HeldOutSet& held_out, bool second_pass) {
    ensure_directory(folder);
    LineChart chart;
    chart.title = "Implicit relighting: PSNR against the regularisation eta (" +
                  std::to_string(held_out.truths.size()) + " held-out lights)";
    chart.x_label = "eta (squared linear pixel units)";
    chart.y_label = "PSNR (dB)";
    chart.log_x = true;
    chart.key_position = "bottom left";
    PlotSeries curve{"MAP estimate", {}, {}};
    const std::optional<std::size_t> pseudo_inverse = pseudo_inverse_of(study);
    for (const EtaStudyPoint& point : study.points)
        if (point.eta > 0.0) curve.x.push_back(point.eta), curve.y.push_back(point.psnr);
    chart.series.push_back(curve);
    if (pseudo_inverse && !curve.x.empty()) {
        const double psnr = study.points[*pseudo_inverse].psnr;
        chart.series.push_back({"pseudo-inverse (eta = 0)", {curve.x.front(), curve.x.back()}, {psnr, psnr}});
    }
    const EtaStudyPoint& best = study.points[study.best];
    chart.vertical_markers.push_back({best.eta, "best"});
    if (model.noise_variance > 0.0) chart.vertical_markers.push_back({model.noise_variance, "noise estimate"});
    bool charted = false;
    if (!curve.x.empty()) {
        try {
            write_line_chart(chart, folder / "eta_psnr");
            charted = true;
        } catch (const ToolError& e) {
            std::fprintf(stderr, "rfd: warning: %s\n", e.what());
        }
    }
    std::vector<std::string> columns{"eta", "psnr_db", "probe_residual_rms", "max_abs_coefficient"};
    for (std::size_t t = 0; t < held_out.truths.size(); ++t)
        columns.push_back("light_" + std::to_string(t) + "_psnr_db");
    CsvTable sweep(std::move(columns));
    for (const auto& point : study.points) {
        std::vector<std::string> row{format_number(point.eta, 8), format_number(point.psnr, 8),
                                     format_number(point.probe_residual_rms, 8),
                                     format_number(point.max_abs_coefficient, 8)};
        for (const double p : point.light_psnr) row.push_back(format_number(p, 8));
        sweep.add_row(std::move(row));
    }
    sweep.write(folder / "eta_sweep.csv");

    // Comparison images: truth | pseudo-inverse | best eta | the largest eta, one exposure.
    const std::size_t largest = static_cast<std::size_t>(
        std::max_element(study.points.begin(), study.points.end(),
                         [](const auto& a, const auto& b) { return a.eta < b.eta; }) -
        study.points.begin());
    std::vector<std::size_t> shown;
    for (const std::optional<std::size_t> i : {pseudo_inverse, std::optional{study.best}, std::optional{largest}})
        if (i && std::find(shown.begin(), shown.end(), *i) == shown.end()) shown.push_back(*i);
    for (std::size_t t = 0; t < held_out.photos.size(); ++t) {
        const float exposure = 0.9f / std::max(percentile(held_out.truths[t], 0.995), 1e-12f);
        std::vector<Image> panels{scaled(held_out.truths[t], exposure)};
        std::vector<Image> probe_panels{scaled(held_out.probes[t], exposure)};
        for (const std::size_t i : shown) {
            const ImplicitFit fit =
                implicit_fit(model, held_out.probes[t], {.eta = study.points[i].eta, .second_pass = second_pass});
            panels.push_back(scaled(relight(training, fit.coefficients()), exposure));
            probe_panels.push_back(scaled(fit.probe, exposure));
        }
        std::vector<const Image*> row, probe_row;
        for (const auto& panel : panels) row.push_back(&panel);
        for (const auto& panel : probe_panels) probe_row.push_back(&panel);
        char name[64];
        std::snprintf(name, sizeof name, "light_%02zu.png", t);
        write_image(folder / name, join_side_by_side(row, 4, 0.5f));
        std::snprintf(name, sizeof name, "light_%02zu_probe.png", t);
        write_image(folder / name, join_side_by_side(probe_row, 4, 0.5f));
    }
    return charted;
}

CsvTable coefficient_table(const ImplicitFit& fit, const std::vector<std::filesystem::path>& images) {
    CsvTable table(fit.l.cols() == 1 ? std::vector<std::string>{"image", "l"}
                                     : std::vector<std::string>{"image", "l_r", "l_g", "l_b"});
    for (Eigen::Index i = 0; i < fit.l.rows(); ++i) {
        std::vector<std::string> row{images[static_cast<std::size_t>(i)].filename().string()};
        for (Eigen::Index c = 0; c < fit.l.cols(); ++c) row.push_back(format_number(fit.l(i, c), 10));
        table.add_row(std::move(row));
    }
    return table;
}

nlohmann::json eta_sweep_json(const EtaStudy& study, const ImplicitModel& model, const std::string& model_name,
                              std::size_t test_lights, bool second_pass, bool charted) {
    const EtaStudyPoint& best = study.points[study.best];
    const std::optional<std::size_t> pseudo_inverse = pseudo_inverse_of(study);
    nlohmann::json points = nlohmann::json::array();
    for (const auto& point : study.points)
        points.push_back({{"eta", point.eta},
                          {"psnr_db", point.psnr},
                          {"probe_residual_rms", point.probe_residual_rms},
                          {"max_abs_coefficient", point.max_abs_coefficient}});
    nlohmann::json summary = {{"model", model_name},
                              {"test_lights", test_lights},
                              {"second_pass", second_pass},
                              {"noise_estimate", model.noise_variance},
                              {"best_eta", best.eta},
                              {"best_psnr_db", best.psnr},
                              {"points", points},
                              {"chart", charted}};
    if (pseudo_inverse) {
        summary["pseudo_inverse_psnr_db"] = study.points[*pseudo_inverse].psnr;
        summary["gain_over_pseudo_inverse_db"] = best.psnr - study.points[*pseudo_inverse].psnr;
    }
    return summary;
}

std::string eta_sweep_text(const EtaStudy& study, const std::string& model_name, const std::string& folder,
                           std::size_t test_lights, std::size_t examples) {
    const EtaStudyPoint& best = study.points[study.best];
    const std::optional<std::size_t> pseudo_inverse = pseudo_inverse_of(study);
    std::string text;
    text += format_text("eta sweep of %s on %zu held-out light(s) -> %s\n", model_name.c_str(),
                  test_lights, folder.c_str());
    text += format_text("  %-12s %10s %14s %12s\n", "eta", "PSNR (dB)", "probe residual", "max |l_i|");
    for (std::size_t i = 0; i < study.points.size(); ++i) {
        const auto& point = study.points[i];
        text += format_text("  %-12.3g %10.2f %14.3g %12.3g%s\n", point.eta, point.psnr,
                      point.probe_residual_rms, point.max_abs_coefficient, i == study.best ? "  <- best" : "");
    }
    if (pseudo_inverse) {
        text += format_text("  best eta %.3g gains %.2f dB over the pseudo-inverse (eta = 0)\n", best.eta,
                      best.psnr - study.points[*pseudo_inverse].psnr);
    }
    if (examples > 0) {
        text += format_text("  comparisons        light_NN.png: truth | %s (same exposure)\n",
                      pseudo_inverse ? "eta = 0 | best eta | largest eta" : "best eta | largest eta");
    }
    return text;
}

}  // namespace rfd::relight
