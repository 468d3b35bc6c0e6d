// rfd relight implicit train / predict: implicit relighting with a probe object (thesis
// chapter 7, relight/implicit.hpp).

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/text.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image_io.hpp"
#include "core/number.hpp"
#include "core/plot.hpp"
#include "core/progress.hpp"
#include "relight/field.hpp"
#include "relight/implicit.hpp"
#include "relight/implicit_study.hpp"
#include "relight/scene.hpp"
#include "relight/stage.hpp"

namespace rfd::cli {
namespace {

namespace fs = std::filesystem;

constexpr const char* kProbeFile = "probe.json";

// --probe-box X,Y,W,H (pixels, continuous image coordinates).
relight::ProbeBox parse_probe_box(const std::string& text) {
    std::vector<double> values;
    std::stringstream in(text);
    std::string item;
    bool all_numbers = true;
    while (std::getline(in, item, ',')) {
        const std::optional<double> value = finite_number(item);
        all_numbers = all_numbers && value.has_value();
        if (value) values.push_back(*value);
    }
    if (!all_numbers || values.size() != 4 || !(values[2] > 0.0 && values[3] > 0.0))
        throw InputError("--probe-box " + text + ": expected X,Y,WIDTH,HEIGHT in pixels with positive size");
    return {values[0], values[1], values[2], values[3]};
}


// probe.json beside a set of photographs (rfd capture implicit writes one), if there is one.
std::optional<relight::ProbeDescription> probe_beside(const fs::path& photos) {
    const fs::path file = (fs::is_directory(photos) ? photos : photos.parent_path()) / kProbeFile;
    if (!fs::exists(file)) return std::nullopt;
    return relight::read_probe_description(file);
}

void add_train(CLI::App& implicit) {
    auto* cmd = implicit.add_subcommand(
        "train", "Learn how a scene answers light from its probe object (PCA of the probe, thesis 7.3)");
    struct Options {
        std::string training, box, out;
        int size = relight::kProbeSize;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("TRAINING", opt->training,
                    "Training images: a folder of images (name order), a field folder or its .lp")
        ->required();
    cmd->add_option("--probe-box", opt->box,
                    "The probe's bounding box X,Y,WIDTH,HEIGHT in pixels (default: probe.json beside the images)");
    cmd->add_option("--probe-size", opt->size, "Probe resolution after scaling")->check(CLI::Range(8, 512));
    cmd->add_option("--out", opt->out, "Model folder to write")->required();
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        const auto t0 = std::chrono::steady_clock::now();
        const std::optional<relight::ProbeDescription> info = probe_beside(opt->training);
        relight::ImplicitModelFiles files;
        if (!opt->box.empty()) files.box = parse_probe_box(opt->box);
        else if (info) files.box = info->box;
        else
            throw InputError("relight implicit train: give --probe-box X,Y,WIDTH,HEIGHT (no probe.json beside " +
                             opt->training + ")");
        if (info) files.probe_material = info->material;
        files.images = relight::training_image_files(opt->training);
        const std::vector<Image> images = relight::read_training_images(files.images);
        std::vector<Image> probes;
        for (std::size_t i = 0; i < images.size(); ++i) {
            try {
                probes.push_back(relight::crop_probe(images[i], files.box, opt->size));
            } catch (const InputError& e) {
                throw InputError(SourceLocation{files.images[i].string()}, e.what());
            }
        }
        const auto t1 = std::chrono::steady_clock::now();
        files.model = relight::train_implicit(probes);
        const auto t2 = std::chrono::steady_clock::now();
        for (const auto& pca : files.model.pca)
            if (pca.w.size() == 0)
                throw InputError(SourceLocation{opt->training},
                                 "the probe looks the same in every training image: nothing to learn the light from");
        relight::write_implicit_model(opt->out, files);
        const auto seconds = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
        std::vector<Eigen::Index> ranks;
        for (const auto& pca : files.model.pca) ranks.push_back(pca.w.size());
        if (opt->json) {
            const nlohmann::json summary = {{"model", opt->out},
                                            {"images", images.size()},
                                            {"probe_box", {files.box.x, files.box.y, files.box.width, files.box.height}},
                                            {"probe_size", opt->size},
                                            {"masked_pixels", files.model.mask.size()},
                                            {"rank", ranks},
                                            {"noise_variance", files.model.noise_variance},
                                            {"read_seconds", seconds(t0, t1)},
                                            {"pca_seconds", seconds(t1, t2)}};
            std::printf("%s\n", summary.dump(2).c_str());
        } else {
            std::printf("trained %s from %zu images of %d x %d\n", opt->out.c_str(), images.size(),
                        images.front().width(), images.front().height());
            std::printf("  probe              box %.1f,%.1f %.1f x %.1f px, scaled to %d x %d (%zu pixels in the disc)\n",
                        files.box.x, files.box.y, files.box.width, files.box.height, opt->size, opt->size,
                        files.model.mask.size());
            std::printf("  principal comps.   %ld per channel\n", static_cast<long>(ranks.front()));
            std::printf("  noise estimate     %.3g (sigma_N^2, a starting eta)\n", files.model.noise_variance);
            std::printf("  time               %.2f s reading, %.3f s PCA\n", seconds(t0, t1), seconds(t1, t2));
        }
    });
}

struct PredictOptions {
    std::string model, probe, box, envmap, out, probe_out, coefficients;
    std::vector<std::string> lights;
    double eta = -1.0;
    bool no_second_pass = false, json = false;
};

// The probe to fit, in the model's channels: cropped from --probe (with --probe-box, or the
// training box when the photograph has the training images' size), or rendered from the
// model's probe material under --light/--envmap.
Image probe_of(const PredictOptions& opt, const relight::ImplicitModelFiles& files) {
    const relight::ImplicitModel& model = files.model;
    Image probe;
    if (!opt.probe.empty()) {
        const Image photo = read_image(opt.probe);
        relight::ProbeBox box{0.0, 0.0, double(photo.width()), double(photo.height())};
        if (!opt.box.empty()) box = parse_probe_box(opt.box);
        else if (fs::exists(files.images.front())) {
            const ImageSize training = read_image_size(files.images.front());
            if (training.width == photo.width() && training.height == photo.height()) box = files.box;
        }
        try {
            probe = relight::crop_probe(photo, box, model.size);
        } catch (const InputError& e) {
            throw InputError(SourceLocation{opt.probe}, e.what());
        }
    } else if (!opt.lights.empty() || !opt.envmap.empty()) {
        if (!files.probe_material)
            throw InputError("relight implicit predict: the model does not know its probe's material (it was not "
                             "trained on a virtual light stage set); photograph the probe and pass --probe");
        std::vector<relight::Light> lights;
        for (const auto& text : opt.lights) lights.push_back(parse_light(text));
        if (!opt.envmap.empty()) lights.push_back(relight::EnvironmentMap{read_image(opt.envmap)});
        const Image synthetic = relight::render_probe(lights, *files.probe_material, model.size);
        probe = relight::crop_probe(synthetic, {0.0, 0.0, double(model.size), double(model.size)}, model.size);
    } else {
        throw InputError("relight implicit predict: give --probe IMAGE, or --light/--envmap for designed lighting");
    }
    if (probe.channels() == model.channels) return probe;
    if (probe.channels() == 3 && model.channels == 1) {
        Image grey(probe.width(), probe.height(), 1);
        for (std::size_t i = 0; i < grey.pixel_count(); ++i)
            grey.plane(0)[i] = (probe.plane(0)[i] + probe.plane(1)[i] + probe.plane(2)[i]) / 3.0f;
        return grey;
    }
    throw InputError("the probe image has " + std::to_string(probe.channels()) + " channel(s); the model was trained on " +
                     std::to_string(model.channels));
}

void add_predict(CLI::App& implicit) {
    auto* cmd = implicit.add_subcommand(
        "predict", "Relight the scene under the light a probe image shows (MAP estimate, thesis 7.3)");
    auto opt = std::make_shared<PredictOptions>();
    cmd->add_option("MODEL", opt->model, "Model folder from `rfd relight implicit train`")->required();
    auto* probe_option = cmd->add_option("--probe", opt->probe,
                                  "Image showing the probe in the new light (a photograph with the probe at "
                                  "--probe-box, or a probe image alone)");
    cmd->add_option("--probe-box", opt->box,
                    "Where --probe shows the probe: X,Y,WIDTH,HEIGHT (default: the training box for an image of "
                    "the training size, else the whole image)");
    auto* light = cmd->add_option("--light", opt->lights,
                                  std::string("Designed lighting: a distant light ") + kLightSyntax +
                                      ", rendered onto a synthetic probe of the model's material; repeatable")
                      ->allow_extra_args(false);
    auto* envmap = cmd->add_option("--envmap", opt->envmap, "Designed lighting: a latitude-longitude environment map");
    probe_option->excludes(light)->excludes(envmap);
    cmd->add_option("--eta", opt->eta,
                    "Regularisation eta = sigma_N^2 in squared pixel units (default: the model's noise estimate, the "
                    "training set's; a noisier photograph wants about its own noise variance or more, which "
                    "`sweep` measures; 0: pseudo-inverse)");
    cmd->add_flag("--no-second-pass", opt->no_second_pass, "Skip the refit of negative probe pixels");
    cmd->add_option("--out", opt->out, "Predicted scene image")->required();
    cmd->add_option("--probe-out", opt->probe_out, "Write the probe and its fit side by side here");
    cmd->add_option("--coefficients", opt->coefficients, "Write the coefficients l_i per channel as CSV here");
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        const auto t0 = std::chrono::steady_clock::now();
        const relight::ImplicitModelFiles files = relight::read_implicit_model(opt->model);
        const relight::ImplicitModel& model = files.model;
        const Image probe = probe_of(*opt, files);
        const double eta = opt->eta >= 0.0 ? opt->eta : model.noise_variance;
        const auto t1 = std::chrono::steady_clock::now();
        const relight::ImplicitFit fit =
            relight::implicit_fit(model, probe, {.eta = eta, .second_pass = !opt->no_second_pass});
        const auto t2 = std::chrono::steady_clock::now();
        const std::vector<Image> images = relight::read_training_images(files.images);
        const auto t3 = std::chrono::steady_clock::now();
        const Image scene = relight::relight(images, fit.coefficients());
        const auto t4 = std::chrono::steady_clock::now();
        for (const float s : scene.samples())
            if (!std::isfinite(s)) throw InputError("the prediction is not finite: is eta far too small for this model?");
        write_image(opt->out, scene);
        if (!opt->probe_out.empty())
            write_image(opt->probe_out, join_side_by_side({&probe, &fit.probe}, 0, 0.0f));
        if (!opt->coefficients.empty()) {
            relight::coefficient_table(fit, files.images).write(opt->coefficients);
        }
        const auto seconds = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
        if (opt->json) {
            const nlohmann::json summary = {{"model", opt->model},
                                            {"out", opt->out},
                                            {"eta", eta},
                                            {"second_pass", !opt->no_second_pass},
                                            {"negative_probe_samples_first_pass", fit.negative_first},
                                            {"negative_probe_samples", fit.negative_final},
                                            {"probe_residual_rms", fit.residual_rms},
                                            {"coefficient_sum", fit.l.colwise().sum()(0)},
                                            {"coefficient_max_abs", fit.l.cwiseAbs().maxCoeff()},
                                            {"fit_seconds", seconds(t1, t2)},
                                            {"read_seconds", seconds(t0, t1) + seconds(t2, t3)},
                                            {"combine_seconds", seconds(t3, t4)}};
            std::printf("%s\n", summary.dump(2).c_str());
        } else {
            std::printf("predicted %s from %zu training images\n", opt->out.c_str(), images.size());
            std::printf("  eta                %.3g%s\n", eta, opt->eta >= 0.0 ? "" : " (the model's noise estimate)");
            std::printf("  probe fit          rms residual %.3g; negative samples %zu -> %zu after the second pass\n",
                        fit.residual_rms, fit.negative_first, fit.negative_final);
            std::printf("  coefficients       largest |l_i| %.3g\n", fit.l.cwiseAbs().maxCoeff());
            std::printf("  time               %.4f s fit, %.4f s combination, %.2f s reading\n", seconds(t1, t2),
                        seconds(t3, t4), seconds(t0, t1) + seconds(t2, t3));
        }
    });
}


// ---- rfd capture implicit -------------------------------------------------------------

// Renders `lights` into a field folder, with camera noise (0: none) seeded per image.
void render_set(const relight::LightStage& stage, const std::vector<relight::StageLight>& lights,
                const fs::path& folder, double noise, std::uint64_t seed, const std::string& label) {
    relight::FieldWriter field(folder);
    Progress progress(label, lights.size());
    for (std::size_t i = 0; i < lights.size(); ++i) {
        Image image = stage.render(lights[i].direction, lights[i].kernel);
        relight::add_camera_noise(image, noise, seed * 0x9E3779B97F4A7C15ull + i);
        field.add(image, lights[i].direction, lights[i].kernel.radius);
        progress.advance();
    }
    progress.finish();
    field.finish();
}

}  // namespace

void add_capture_implicit_command(CLI::App& capture) {
    auto* cmd = capture.add_subcommand(
        "implicit", "Training and held-out test sets for implicit relighting on the virtual light stage (7.4)");
    struct Options {
        std::string scene, out, probe, resolution;
        int samples = 0;
        std::size_t lights = 272, held_out = 16;
        double noise = 1e-4, test_noise = 3e-3;
        std::uint64_t seed = 1;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("SCENE", opt->scene, "Scene file (TOML) with a probe sphere, e.g. scenes/snooker.toml")->required();
    cmd->add_option("--out", opt->out, "Folder to write: training/, test/photos/, test/truth/")->required();
    cmd->add_option("--lights", opt->lights,
                    "Training lights: overlapping smooth lights of 15, 25 and 40 degrees radius")
        ->check(CLI::Range(2, 100000));
    cmd->add_option("--held-out", opt->held_out, "Held-out test lights: smooth, 10 to 25 degrees radius, random directions")
        ->check(CLI::Range(0, 10000));
    cmd->add_option("--probe", opt->probe,
                    "Name of the probe object (default: the scene's only sphere of a phong material)");
    cmd->add_option("--noise", opt->noise,
                    "Camera noise of the training images, standard deviation in linear radiance ("
                    "an HDR capture)")
        ->check(CLI::Range(0.0, 1e3));
    cmd->add_option("--test-noise", opt->test_noise,
                    "Camera noise of the test photographs (one 8-bit exposure: about 2 levels "
                    "where the card's white is 0.35; the truth has none)")
        ->check(CLI::Range(0.0, 1e3));
    cmd->add_option("--seed", opt->seed, "Seed of the light pattern and the noise");
    cmd->add_option("--resolution", opt->resolution, "Image size WxH (default: the scene's)");
    cmd->add_option("--samples-per-pixel", opt->samples, "Camera rays per pixel (default: the scene's)")
        ->check(CLI::Range(1, 4096));
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        const auto t0 = std::chrono::steady_clock::now();
        relight::Scene scene = relight::load_scene(opt->scene);
        apply_scene_overrides(scene, opt->resolution, opt->samples);
        const relight::SceneObject& probe = relight::probe_object(scene, opt->probe, opt->scene);
        const auto& sphere = std::get<relight::SphereShape>(probe.shape);
        const Eigen::Vector4d box = scene.cameras.front().sphere_box(sphere.centre, sphere.radius);
        const relight::Camera& camera = scene.cameras.front();
        if (!(box[0] >= 0.0 && box[1] >= 0.0 && box[0] + box[2] <= camera.width && box[1] + box[3] <= camera.height))
            throw InputError(SourceLocation{opt->scene}, "the probe " + probe.name + " is not wholly inside the image");
        relight::ProbeDescription description{{box[0], box[1], box[2], box[3]}, std::nullopt};
        if (const auto* phong = std::get_if<relight::PhongMaterial>(&scene.materials[probe.material]))
            if (std::holds_alternative<relight::Rgb>(phong->albedo)) description.material = *phong;

        const fs::path out(opt->out);
        const relight::LightStage stage(std::move(scene));
        // probe.json before the light files: a field that can be read has its probe described.
        const auto training = relight::implicit_training_lights(opt->lights, opt->seed);
        ensure_directory(out / "training");
        relight::write_probe_description(out / "training" / kProbeFile, description);
        render_set(stage, training, out / "training", opt->noise, opt->seed, "training lights");
        if (opt->held_out > 0) {
            const auto test = relight::held_out_lights(opt->held_out, opt->seed + 1);
            ensure_directory(out / "test" / "photos");
            relight::write_probe_description(out / "test" / "photos" / kProbeFile, description);
            render_set(stage, test, out / "test" / "truth", 0.0, 0, "held-out lights, truth");
            render_set(stage, test, out / "test" / "photos", opt->test_noise, ~opt->seed, "held-out lights, photos");
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const double per_light = seconds / static_cast<double>(opt->lights + 2 * opt->held_out);
        if (opt->json) {
            nlohmann::json summary = {{"scene", opt->scene},
                                      {"out", opt->out},
                                      {"probe", probe.name},
                                      {"probe_box", {box[0], box[1], box[2], box[3]}},
                                      {"training_lights", opt->lights},
                                      {"held_out_lights", opt->held_out},
                                      {"noise", opt->noise},
                                      {"test_noise", opt->test_noise},
                                      {"seed", opt->seed},
                                      {"seconds", seconds}};
            std::printf("%s\n", summary.dump(2).c_str());
        } else {
            std::printf("rendered %zu training and %zu held-out light(s) of %s into %s\n", opt->lights, opt->held_out,
                        opt->scene.c_str(), opt->out.c_str());
            std::printf("  probe              %s, box %.1f,%.1f %.1f x %.1f px%s\n", probe.name.c_str(), box[0],
                        box[1], box[2], box[3],
                        description.material ? "" : " (not phong: no synthetic probes for designed lighting)");
            std::printf("  camera noise       %.3g training, %.3g test photos (standard deviation)\n", opt->noise,
                        opt->test_noise);
            std::printf("  time               %.1f s, %.3f s per image\n", seconds, per_light);
        }
    });
}

namespace {

// ---- rfd relight implicit sweep ----------------------------------------------------------

void add_sweep(CLI::App& implicit) {
    auto* cmd = implicit.add_subcommand(
        "sweep", "PSNR against eta on held-out lights with known truth: noise against detail (figure 7.3)");
    struct Options {
        std::string model, test, out, etas;
        std::size_t examples = 3;
        bool no_second_pass = false, json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("MODEL", opt->model, "Model folder from `rfd relight implicit train`")->required();
    cmd->add_option("--test", opt->test,
                    "Held-out set: a folder with photos/ (fields of photographs showing the probe) and truth/ (the "
                    "scene under the same lights, clean), as `rfd capture implicit` writes test/")
        ->required();
    cmd->add_option("--etas", opt->etas,
                    "Comma-separated etas (default: 0, then half decades from 1e-6 to 1e2 times the mean square of "
                    "the model's mean probe)");
    cmd->add_option("--examples", opt->examples, "Comparison images for the first N test lights")
        ->check(CLI::Range(0, 1000));
    cmd->add_flag("--no-second-pass", opt->no_second_pass, "Skip the refit of negative probe pixels");
    cmd->add_option("--out", opt->out, "Folder for eta_psnr.{csv,gp,svg,png} and the comparison images")->required();
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        const relight::ImplicitModelFiles files = relight::read_implicit_model(opt->model);
        const relight::ImplicitModel& model = files.model;
        std::vector<double> etas;
        if (opt->etas.empty()) {
            etas = relight::default_eta_grid(model);
        } else {
            std::stringstream in(opt->etas);
            std::string item;
            while (std::getline(in, item, ',')) {
                const std::optional<double> eta = finite_number(item);
                if (!eta || *eta < 0.0)
                    throw InputError("--etas: expected comma-separated numbers >= 0, got '" + item + "'");
                etas.push_back(*eta);
            }
            if (etas.empty()) throw InputError("--etas: expected at least one eta");
        }
        const std::vector<Image> training = relight::read_training_images(files.images);
        const relight::HeldOutSet held_out =
            relight::read_held_out_set(opt->test, files, training.front(), opt->examples);
        const bool second_pass = !opt->no_second_pass;
        const relight::EtaStudy study =
            relight::study_eta(model, training, held_out.probes, held_out.truths, etas, second_pass);
        const bool charted = relight::write_eta_sweep_report(opt->out, study, model, training, held_out, second_pass);
        if (opt->json)
            std::printf("%s\n", relight::eta_sweep_json(study, model, opt->model, held_out.truths.size(), second_pass,
                                                        charted)
                                    .dump(2)
                                    .c_str());
        else
            std::fputs(relight::eta_sweep_text(study, opt->model, opt->out, held_out.truths.size(),
                                               held_out.photos.size())
                           .c_str(),
                       stdout);
    });
}

}  // namespace

void add_implicit_commands(CLI::App& relight) {
    CLI::App* implicit =
        relight.add_subcommand("implicit", "Implicit relighting with a probe object (thesis chapter 7)")
            ->require_subcommand(1);
    add_train(*implicit);
    add_predict(*implicit);
    add_sweep(*implicit);
}

}  // namespace rfd::cli
