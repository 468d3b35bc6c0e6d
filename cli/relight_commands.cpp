// rfd relight render / eval: relighting a reflectance field (thesis 4.2, 4.4) and measuring
// how well a sparse field predicts a reference (5.2, figure 5.4).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/json.hpp"
#include "core/text.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image_io.hpp"
#include "core/plot.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/basis.hpp"
#include "relight/evaluate.hpp"
#include "relight/field.hpp"
#include "relight/fit_file.hpp"
#include "relight/light_model.hpp"
#include "relight/interpolation.hpp"
#include "relight/render.hpp"

namespace rfd::cli {
namespace {

// The width of a model that has one (rbf, bilinear): `given` (--sigma) when positive, else
// the one of least leave-one-out error on the field; the field's Gram matrix is read once,
// into `gram`, for every model that needs it.
void choose_sigma(relight::LightModel& model, double given, relight::FieldReader& field,
                  std::optional<relight::FieldGram>& gram) {
    if (!model.has_sigma()) return;
    if (given > 0.0) {
        model.sigma = given;
        return;
    }
    if (!gram) gram = relight::field_gram(field);
    model.sigma = relight::best_sigma(*gram, field.directions(), model);
}

// The lights of --light and --light-dir in the order they were given, with their texts.
struct OrderedLights {
    std::vector<relight::Light> lights;
    std::vector<std::string> texts;
};

OrderedLights ordered_lights(const CLI::App& cmd, const CLI::Option* light, const CLI::Option* light_dir,
                             const std::vector<std::string>& angles, const std::vector<std::string>& directions) {
    OrderedLights out;
    std::size_t next_angles = 0, next_direction = 0;
    for (const CLI::Option* option : cmd.parse_order()) {
        if (option == light && next_angles < angles.size()) {
            out.texts.push_back(angles[next_angles]);
            out.lights.push_back(parse_light(angles[next_angles++]));
        } else if (option == light_dir && next_direction < directions.size()) {
            out.texts.push_back(directions[next_direction]);
            out.lights.push_back(parse_light_direction(directions[next_direction++]));
        }
    }
    return out;
}

// A fit's folder (or its info.json) rather than a field's.
bool is_fit(const std::filesystem::path& path) {
    return path.filename() == "info.json" || std::filesystem::is_regular_file(path / "info.json");
}

// relight render FIT: one distant light per output, each written a band of rows at a time.
void render_fit(const std::filesystem::path& fit, const OrderedLights& given, const std::string& light_file,
                const std::vector<std::string>& out_names, bool field_options) {
    if (field_options)
        throw InputError("relight render: " + fit.string() +
                         " is a fit; --envmap, --basis, --region and --scale are for fields");
    std::vector<relight::Light> lights = given.lights;
    std::vector<std::filesystem::path> outs;
    if (!light_file.empty()) {
        if (out_names.size() != 1)
            throw InputError("relight render: with --lights, give one --out: the folder for its images");
        ensure_directory(out_names.front());
        bool radii = false;
        for (const relight::LightEntry& entry : relight::read_light_file(light_file)) {
            radii = radii || entry.kernel_radius > 0.0;
            lights.push_back(relight::DirectionalLight{entry.direction});
            outs.push_back(std::filesystem::path(out_names.front()) / entry.file);
        }
        if (radii)
            std::fprintf(stderr, "note: %s gives its lights' disc radii; a fit is relit under point lights toward "
                                 "their centres\n", light_file.c_str());
    } else {
        if (lights.empty()) throw InputError("relight render: give at least one --light, --light-dir or --lights");
        if (out_names.size() != lights.size())
            throw InputError("relight render: a fit is relit into one --out per light; " +
                             std::to_string(out_names.size()) + " --out for " + std::to_string(lights.size()) +
                             " lights");
        for (const std::string& name : out_names) outs.emplace_back(name);
    }
    std::vector<Eigen::Vector3d> directions;
    for (const relight::Light& light : lights) {
        const auto* directional = std::get_if<relight::DirectionalLight>(&light);
        if (directional == nullptr || !directional->irradiance.isOnes())
            throw InputError("relight render: a fit is relit under white distant point lights (no RADIUS, no "
                             "colour); relight the field itself for disks and coloured light");
        directions.push_back(directional->direction.normalized());
    }
    const relight::FitFile file = relight::read_fit(fit);
    relight::render_fit_to_files(fit, directions, outs);
    std::printf("relit the %s fit %s (%d x %d, %d planes, %s) into %zu image(s)\n",
                relight::fit_type_name(file.type),
                fit.string().c_str(), file.width, file.height, file.nplanes,
                file.exact ? "linear float planes" : "8-bit planes of display values", outs.size());
}

void add_render(CLI::App& relight) {
    auto* cmd = relight.add_subcommand(
        "render", "Relight a reflectance field under distant lights or an environment map, read a band of rows at "
                  "a time (a field may be larger than memory)");
    struct Options {
        std::string field, envmap, light_file, interpolation = "delaunay", basis;
        std::vector<std::string> lights, light_dirs, outs;
        double sigma = 0.0;
        bool json = false;
        WindowOptions window;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("FIELD", opt->field,
                    "Reflectance field folder or .lp file, or a fit (a folder with info.json: relight fit's, or "
                    "CNR relight's)")
        ->required();
    add_window_options(*cmd, opt->window);
    auto* light = cmd->add_option("--light", opt->lights,
                                  std::string("A distant light ") + kLightSyntax +
                                      "; with RADIUS a disk of that angular radius; repeat to add lights")
                      ->allow_extra_args(false);
    auto* light_dir = cmd->add_option("--light-dir", opt->light_dirs,
                                      std::string("A distant light toward ") + kLightDirectionSyntax +
                                          "; repeat to add lights")
                          ->allow_extra_args(false);
    auto* light_file = cmd->add_option("--lights", opt->light_file,
                                       "A light file (.lp: per line OUTPUT X Y Z [RADIUS_DEG]): one image per line, "
                                       "named as the line says, into the --out folder, all in one pass");
    auto* envmap = cmd->add_option("--envmap", opt->envmap,
                                   "Latitude-longitude environment map (EXR/HDR radiance; row 0 at the zenith, "
                                   "centre column toward +x)");
    light->excludes(envmap)->excludes(light_file);
    light_dir->excludes(envmap)->excludes(light_file);
    light_file->excludes(envmap);
    cmd->add_option("--out", opt->outs,
                    "Output image (.exr linear, .png sRGB, ...): one for the lights summed, or one per --light / "
                    "--light-dir in their order; with --lights, a folder")
        ->required()
        ->allow_extra_args(false);
    cmd->add_option("--interpolation", opt->interpolation, "delaunay, solid-angle (eq. 4.6 as written) or nearest");
    cmd->add_option("--basis", opt->basis,
                    "Predict the lights with this instead of --interpolation: ptm, hsh2, hsh3, hsh4 (bases fitted to "
                    "the field's lights), rbf (radial basis functions) or bilinear (CNR relight's grid of directions; "
                    "both relight/light_model.hpp); each light is "
                    "still a weighted sum of the images");
    cmd->add_option("--sigma", opt->sigma, "With --basis rbf (or bilinear, its prior), the Gaussian's width (default: "
                                           "least leave-one-out error on the field, one more pass over it)")
        ->check(CLI::PositiveNumber);
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt, cmd, light, light_dir] {
        const relight::Interpolation method = parse_interpolation(opt->interpolation);
        if (is_fit(opt->field)) {
            render_fit(opt->field, ordered_lights(*cmd, light, light_dir, opt->lights, opt->light_dirs), opt->light_file,
                       opt->outs, !opt->envmap.empty() || !opt->basis.empty() || !opt->window.region.empty());
            return;
        }
        const OrderedLights given = ordered_lights(*cmd, light, light_dir, opt->lights, opt->light_dirs);
        // Each output image and the lights it sums.
        std::vector<std::vector<relight::Light>> renders;
        std::vector<std::filesystem::path> outs;
        std::vector<std::string> names;
        if (!opt->light_file.empty()) {
            if (opt->outs.size() != 1)
                throw InputError("relight render: with --lights, give one --out: the folder for its images");
            for (const relight::LightEntry& entry : relight::read_light_file(opt->light_file)) {
                relight::Light one = relight::DirectionalLight{entry.direction};
                if (entry.kernel_radius > 0.0) one = relight::DiskLight{entry.direction, entry.kernel_radius};
                renders.push_back({one});
                outs.push_back(std::filesystem::path(opt->outs.front()) / entry.file);
                names.push_back(entry.file);
            }
            if (renders.empty()) throw InputError(SourceLocation{opt->light_file}, "the light file lists no light");
            ensure_directory(opt->outs.front());
        } else if (!opt->envmap.empty()) {
            if (opt->outs.size() != 1) throw InputError("relight render: with --envmap, give one --out");
            Image map = read_image(opt->envmap);
            if (map.width() != 2 * map.height())
                throw InputError(SourceLocation{opt->envmap},
                                 "a latitude-longitude map is twice as wide as high; this one is " +
                                     std::to_string(map.width()) + " x " + std::to_string(map.height()));
            try {
                relight::check_environment_map(map);
            } catch (const InputError& error) {
                throw InputError(SourceLocation{opt->envmap}, error.what());
            }
            renders.push_back({relight::EnvironmentMap{std::move(map)}});
            outs.emplace_back(opt->outs.front());
            names.push_back(opt->envmap);
        } else if (given.lights.empty()) {
            throw InputError("relight render: give at least one --light, --light-dir, --lights or --envmap");
        } else if (opt->outs.size() == 1) {
            renders.push_back(given.lights);
            outs.emplace_back(opt->outs.front());
            names.push_back(given.texts.size() == 1 ? given.texts.front()
                                                    : std::to_string(given.texts.size()) + " lights summed");
        } else if (opt->outs.size() == given.lights.size()) {
            for (std::size_t j = 0; j < given.lights.size(); ++j) {
                renders.push_back({given.lights[j]});
                outs.emplace_back(opt->outs[j]);
                names.push_back(given.texts[j]);
            }
        } else {
            throw InputError("relight render: " + std::to_string(opt->outs.size()) + " --out for " +
                             std::to_string(given.lights.size()) +
                             " lights; give one --out (the lights summed) or one per light, in their order");
        }
        const auto t0 = std::chrono::steady_clock::now();
        relight::FieldReader field(opt->field, opt->window.window());
        std::vector<relight::LightCoefficients> coefficients;
        std::string predictor = opt->interpolation + " interpolation";
        if (!opt->basis.empty()) {
            relight::LightModel model = relight::parse_light_model(opt->basis);
            std::optional<relight::FieldGram> gram;
            choose_sigma(model, opt->sigma, field, gram);
            const relight::LightWeights weights(model, field.directions());
            for (const auto& lights : renders) coefficients.push_back(relight::light_coefficients(weights, lights));
            predictor = model.name();
        } else {
            const relight::SphericalInterpolator interpolator(field.directions());
            for (const auto& lights : renders)
                coefficients.push_back(relight::light_coefficients(interpolator, lights, method));
        }
        const auto t1 = std::chrono::steady_clock::now();
        const std::size_t decoded = relight::relight_to_files(field, coefficients, outs);
        const auto t2 = std::chrono::steady_clock::now();
        const auto seconds = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
        if (opt->json) {
            nlohmann::json images = nlohmann::json::array();
            for (std::size_t j = 0; j < outs.size(); ++j) {
                const Eigen::Vector3d k_sum = coefficients[j].k.colwise().sum().transpose();
                images.push_back({{"out", outs[j].string()},
                                  {"light", names[j]},
                                  {"lights", renders[j].size()},
                                  {"weight_evaluations", coefficients[j].weight_evaluations},
                                  {"nonzero_weights", coefficients[j].nonzero},
                                  {"sum_of_weights_rgb", {k_sum[0], k_sum[1], k_sum[2]}}});
            }
            const nlohmann::json summary = {{"field", opt->field},
                                            {"images", field.size()},
                                            {"images_decoded", decoded},
                                            {"interpolation", opt->interpolation},
                                            {"predictor", predictor},
                                            {"resolution", {field.width(), field.height()}},
                                            {"outputs", std::move(images)},
                                            {"weights_seconds", seconds(t0, t1)},
                                            {"read_and_relight_seconds", seconds(t1, t2)}};
            std::printf("%s\n", summary.dump(2).c_str());
            return;
        }
        std::printf("relit %s (%zu images) into %zu image(s), %s\n", opt->field.c_str(), field.size(), outs.size(),
                    predictor.c_str());
        std::printf("  image              %d x %d, %d channel(s) in the field\n", field.width(), field.height(),
                    field.channels());
        for (std::size_t j = 0; j < outs.size(); ++j) {
            const Eigen::Vector3d k_sum = coefficients[j].k.colwise().sum().transpose();
            std::printf("  %s (%s): non-zero weights %zu of %zu images, sum %.6g %.6g %.6g (R G B)\n",
                        outs[j].string().c_str(), names[j].c_str(), coefficients[j].nonzero, field.size(), k_sum[0],
                        k_sum[1], k_sum[2]);
        }
        std::printf("  read               %zu of %zu images decoded, each once, a band of rows at a time\n", decoded,
                    field.size());
        std::printf("  time               %.4f s weights, %.3f s read and relight\n", seconds(t0, t1),
                    seconds(t1, t2));
    });
}

struct EvalOptions {
    std::string field, reference, out, interpolation = "delaunay";
    std::vector<std::string> lights, bases;
    double sigma = 0.0;
    bool json = false, leave_one_out = false;
    WindowOptions window;
};

// The JSON summary both kinds of evaluation share; `entries` is "per_direction" or "per_light".
nlohmann::json evaluation_summary(const EvalOptions& opt, std::size_t images, std::size_t reference_images,
                                  const relight::Evaluation& e, const char* entries, nlohmann::json per_entry) {
    return {{"field", opt.field},
            {"reference", opt.reference},
            {"interpolation", opt.interpolation},
            {"images", images},
            {"reference_images", reference_images},
            {"peak", e.peak},
            {"total_squared_error", e.total_squared_error},
            {"psnr_db", finite_or_null(e.psnr)},
            {entries, std::move(per_entry)}};
}

// relight eval --light: one score per light, pictures of both relit fields side by side.
void evaluate_under_lights(const EvalOptions& opt, const relight::ReflectanceField& sparse,
                           const relight::ReflectanceField& reference, const std::vector<relight::Light>& lights,
                           relight::Interpolation method) {
    const relight::LightEvaluation evaluation = relight::evaluate_under_lights(sparse, reference, lights, method);
    const relight::Evaluation& e = evaluation.score;
    if (!opt.out.empty()) {
        const std::filesystem::path out(opt.out);
        ensure_directory(out);
        CsvTable errors({"light", "squared_error", "psnr_db"});
        for (std::size_t j = 0; j < lights.size(); ++j)
            errors.add_row({opt.lights[j], format_number(e.per_direction[j], 10), format_number(e.entry_psnr(j), 10)});
        errors.write(out / "errors.csv");
        for (std::size_t j = 0; j < lights.size(); ++j)
            write_image((out / ("light_" + std::to_string(j) + ".png")).string(),
                        join_side_by_side({&evaluation.relit[j], &evaluation.reference_relit[j]}, 2, 0.0f));
    }
    if (opt.json) {
        nlohmann::json per_light = nlohmann::json::array();
        for (std::size_t j = 0; j < lights.size(); ++j)
            per_light.push_back({{"light", opt.lights[j]},
                                 {"squared_error", e.per_direction[j]},
                                 {"psnr_db", finite_or_null(e.entry_psnr(j))}});
        const nlohmann::json summary =
            evaluation_summary(opt, sparse.size(), reference.size(), e, "per_light", std::move(per_light));
        std::printf("%s\n", summary.dump(2).c_str());
        return;
    }
    std::printf("%s (%zu images) against %s (%zu images) under %zu light(s), %s interpolation\n", opt.field.c_str(),
                sparse.size(), opt.reference.c_str(), reference.size(), lights.size(), opt.interpolation.c_str());
    std::printf("  summed squared error  %.6g\n", e.total_squared_error);
    std::printf("  PSNR                  %.2f dB (peak %.6g)\n", e.psnr, e.peak);
    for (std::size_t j = 0; j < lights.size(); ++j)
        std::printf("  %-24s %14.6g %9.2f dB\n", opt.lights[j].c_str(), e.per_direction[j], e.entry_psnr(j));
    if (!opt.out.empty())
        std::printf("  wrote %s/errors.csv and light_K.png (field | reference)\n", opt.out.c_str());
}

// The models --basis names ("all": every one), --interpolation's when none.
std::vector<relight::LightModel> parse_models(const std::vector<std::string>& names, const std::string& interpolation) {
    std::vector<std::string> all;
    for (const std::string& name : names) {
        if (name == "all") {
            for (const std::string& n : relight::light_model_names())
                if (n == interpolation || relight::parse_light_model(n).kind != relight::LightModel::Kind::Interpolation)
                    all.push_back(n);
        } else {
            all.push_back(name);
        }
    }
    if (all.empty()) all.push_back(interpolation);
    std::vector<relight::LightModel> out;
    for (const std::string& name : all) out.push_back(relight::parse_light_model(name));
    return out;
}

// relight eval --leave-one-out: per image of the field and per way of predicting it, both
// PSNRs, and their means.
void evaluate_leave_one_out(const EvalOptions& opt) {
    std::vector<relight::LightModel> models = parse_models(opt.bases, opt.interpolation);
    relight::FieldReader field(opt.field, opt.window.window());
    const int width = field.width(), height = field.height();
    if (field.size() < 4)
        throw InputError(SourceLocation{field.light_file().string()},
                         "leave-one-out needs at least 4 images (3 left to interpolate from); the field has " + std::to_string(field.size()));
    std::optional<relight::FieldGram> gram;
    for (relight::LightModel& model : models) choose_sigma(model, opt.sigma, field, gram);
    std::vector<relight::LightWeights> weights;
    for (const relight::LightModel& model : models) weights.emplace_back(model, field.directions());
    std::vector<const relight::LightWeights*> pointers;
    for (const relight::LightWeights& w : weights) pointers.push_back(&w);
    const std::vector<relight::LeaveOneOut> scores = relight::leave_one_out(field, pointers);
    std::vector<std::string> names;
    for (const relight::LightModel& model : models) names.push_back(model.name());
    const relight::LeaveOneOut& first = scores.front();
    const std::size_t n = first.squared_error.size();
    const bool eight_bit = first.eight_bit();
    const auto text = [](double db) {
        char buffer[32];
        std::snprintf(buffer, sizeof buffer, "%.2f", db);
        return std::isnan(db) ? std::string("-") : std::string(buffer);
    };
    if (!opt.out.empty()) {
        const std::filesystem::path out(opt.out);
        ensure_directory(out);
        std::vector<std::string> header{"index", "theta_deg", "phi_deg"};
        for (const relight::LightModel& model : models) {
            const std::string name = model.base_name();
            if (eight_bit) header.push_back("psnr_srgb8_db_" + name);
            header.push_back("psnr_linear_db_" + name);
            header.push_back("ssim_" + name);
        }
        CsvTable errors(header);
        for (std::size_t j = 0; j < n; ++j) {
            const SphericalAngles a = angles_of(first.directions[j]);
            std::vector<std::string> row{std::to_string(j), format_number(radians_to_degrees(a.theta), 10),
                                         format_number(radians_to_degrees(a.phi), 10)};
            for (const relight::LeaveOneOut& loo : scores) {
                if (eight_bit) row.push_back(format_number(loo.psnr_srgb8(j), 10));
                row.push_back(format_number(loo.psnr_linear(j), 10));
                row.push_back(format_number(loo.ssim[j], 10));
            }
            errors.add_row(row);
        }
        errors.write(out / "leave_one_out.csv");
    }
    if (opt.json) {
        nlohmann::json per_basis = nlohmann::json::object();
        for (std::size_t b = 0; b < names.size(); ++b) {
            const relight::LeaveOneOut& loo = scores[b];
            nlohmann::json per_light = nlohmann::json::array();
            for (std::size_t j = 0; j < n; ++j) {
                const SphericalAngles a = angles_of(loo.directions[j]);
                per_light.push_back({{"theta_deg", radians_to_degrees(a.theta)},
                                     {"phi_deg", radians_to_degrees(a.phi)},
                                     {"psnr_srgb8_db", eight_bit ? finite_or_null(loo.psnr_srgb8(j)) : nullptr},
                                     {"psnr_linear_db", finite_or_null(loo.psnr_linear(j))},
                                     {"ssim", finite_or_null(loo.ssim[j])}});
            }
            per_basis[models[b].base_name()] = {
                {"mean_psnr_srgb8_db", eight_bit ? finite_or_null(loo.mean_psnr_srgb8()) : nullptr},
                {"mean_psnr_linear_db", finite_or_null(loo.mean_psnr_linear())},
                {"mean_ssim", finite_or_null(loo.mean_ssim())},
                {"sigma", models[b].has_sigma() ? nlohmann::json(models[b].sigma) : nlohmann::json()},
                {"per_light", std::move(per_light)}};
        }
        const nlohmann::json summary = {{"field", opt.field},       {"images", n},
                                        {"eight_bit", eight_bit},   {"peak", first.peak},
                                        {"bases", std::move(per_basis)}};
        std::printf("%s\n", summary.dump(2).c_str());
        return;
    }
    std::printf("%s (%zu images, %d x %d): each image predicted from the others\n", opt.field.c_str(), n, width,
                height);
    std::printf("  %-14s %24s %34s %14s\n", "", eight_bit ? "PSNR, 8-bit sRGB codes" : "",
                ("PSNR linear (peak " + format_number(first.peak, 4) + ")").c_str(), "SSIM, sRGB");
    for (std::size_t b = 0; b < names.size(); ++b) {
        char ssim[32];
        std::snprintf(ssim, sizeof ssim, "%.4f", scores[b].mean_ssim());
        std::printf("  mean %-9s %21s dB %31s dB %14s\n", names[b].c_str(),
                    eight_bit ? text(scores[b].mean_psnr_srgb8()).c_str() : "-",
                    text(scores[b].mean_psnr_linear()).c_str(), ssim);
    }
    if (!eight_bit) std::printf("  (the images are not 8-bit: no PSNR in 8-bit codes)\n");
    std::printf("  per image, PSNR %s in dB:\n  %5s %8s %8s", eight_bit ? "in 8-bit sRGB codes" : "linear",
                "index", "theta", "phi");
    for (const std::string& name : names) std::printf(" %9s", name.c_str());
    std::printf("\n");
    for (std::size_t j = 0; j < n; ++j) {
        const SphericalAngles a = angles_of(first.directions[j]);
        std::printf("  %5zu %8.2f %8.2f", j, radians_to_degrees(a.theta), radians_to_degrees(a.phi));
        for (const relight::LeaveOneOut& loo : scores)
            std::printf(" %9s", text(eight_bit ? loo.psnr_srgb8(j) : loo.psnr_linear(j)).c_str());
        std::printf("\n");
    }
    if (!opt.out.empty()) std::printf("  wrote %s/leave_one_out.csv\n", opt.out.c_str());
}

void add_eval(CLI::App& relight) {
    auto* cmd = relight.add_subcommand(
        "eval", "Relight every reference direction from a sparse field and report the error (thesis figure 5.4)");
    auto opt = std::make_shared<EvalOptions>();
    cmd->add_option("FIELD", opt->field, "Sparse reflectance field (folder or .lp)")->required();
    auto* reference_option = cmd->add_option("--reference", opt->reference, "Reference field, same view and image size");
    auto* loo = cmd->add_flag("--leave-one-out", opt->leave_one_out,
                              "Judge the field alone: every image predicted from the others and compared with it "
                              "(PSNR in 8-bit sRGB for 8-bit captures, and linear), read a band of rows at a time");
    loo->excludes(reference_option);
    cmd->add_option("--basis", opt->bases,
                    "With --leave-one-out, how each image is predicted: delaunay, solid-angle, nearest "
                    "(interpolation), ptm, hsh2, hsh3, hsh4 (fitted bases, relight/basis.hpp), rbf (radial basis "
                    "functions), bilinear (CNR relight's grid of directions; both relight/light_model.hpp) or all; "
                    "repeat to compare, all in one pass over the field "
                    "(default: --interpolation)")
        ->needs(loo)
        ->allow_extra_args(false);
    cmd->add_option("--sigma", opt->sigma,
                    "With --basis rbf (or bilinear, its prior), the Gaussian's width (default: least leave-one-out "
                    "error on the field)")
        ->check(CLI::PositiveNumber);
    add_window_options(*cmd, opt->window);
    cmd->add_option("--interpolation", opt->interpolation, "delaunay, solid-angle (eq. 4.6 as written) or nearest");
    cmd->add_option("--light", opt->lights,
                    std::string("Score under this light ") + kLightSyntax +
                        " instead of at every reference direction: both fields relit and compared; with RADIUS a "
                        "disk; repeat for several")
        ->allow_extra_args(false);
    cmd->add_option("--out", opt->out,
                    "Folder for errors.csv and the polar error map error_map.{csv,gp,svg,png}; with --light, "
                    "errors.csv and light_K.png per light (the field relit | the reference relit)");
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        const relight::Interpolation method = parse_interpolation(opt->interpolation);
        if (opt->leave_one_out) {
            if (!opt->lights.empty()) throw InputError("relight eval: --leave-one-out scores the field's own lights; "
                                                       "leave out --light");
            evaluate_leave_one_out(*opt);
            return;
        }
        if (opt->reference.empty())
            throw InputError("relight eval: give --reference FIELD, or --leave-one-out to judge the field alone");
        std::vector<relight::Light> lights;
        for (const auto& text : opt->lights) lights.push_back(parse_light(text));
        // The same part of the same view in both fields.
        const relight::ImageWindow window = opt->window.window();
        const relight::ReflectanceField sparse = relight::read_field(opt->field, window);
        const relight::ReflectanceField reference = relight::read_field(opt->reference, window);
        if (!lights.empty()) {
            evaluate_under_lights(*opt, sparse, reference, lights, method);
            return;
        }
        const relight::Evaluation e = relight::evaluate(sparse, reference, method);
        if (!opt->out.empty()) {
            const std::filesystem::path out(opt->out);
            ensure_directory(out);
            CsvTable errors({"index", "theta_deg", "phi_deg", "squared_error", "psnr_db"});
            for (std::size_t j = 0; j < reference.size(); ++j) {
                const SphericalAngles a = angles_of(reference.directions[j]);
                errors.add_row({std::to_string(j), format_number(radians_to_degrees(a.theta), 10),
                                format_number(radians_to_degrees(a.phi), 10), format_number(e.per_direction[j], 10),
                                format_number(e.entry_psnr(j), 10)});
            }
            errors.write(out / "errors.csv");
            // A few directions (highlights, shadow edges) often dominate: a log scale shows
            // the rest too, when every error is positive.
            const bool all_positive = std::all_of(e.per_direction.begin(), e.per_direction.end(),
                                                  [](double v) { return v > 0.0; });
            write_polar_map({"squared error per reference direction (" + opt->interpolation + ", " +
                                 std::to_string(sparse.size()) + " images)",
                             reference.directions, e.per_direction, "summed squared error", all_positive},
                            out / "error_map");
        }
        if (opt->json) {
            nlohmann::json per_direction = nlohmann::json::array();
            for (std::size_t j = 0; j < reference.size(); ++j) {
                const SphericalAngles a = angles_of(reference.directions[j]);
                per_direction.push_back({{"theta_deg", radians_to_degrees(a.theta)},
                                         {"phi_deg", radians_to_degrees(a.phi)},
                                         {"squared_error", e.per_direction[j]},
                                         {"psnr_db", finite_or_null(e.entry_psnr(j))}});
            }
            const nlohmann::json summary =
                evaluation_summary(*opt, sparse.size(), reference.size(), e, "per_direction", std::move(per_direction));
            std::printf("%s\n", summary.dump(2).c_str());
            return;
        }
        std::printf("%s (%zu images) against %s (%zu images), %s interpolation\n", opt->field.c_str(), sparse.size(),
                    opt->reference.c_str(), reference.size(), opt->interpolation.c_str());
        std::printf("  summed squared error  %.6g\n", e.total_squared_error);
        std::printf("  PSNR                  %.2f dB (peak %.6g)\n", e.psnr, e.peak);
        std::printf("  %5s %9s %9s %14s %9s\n", "index", "theta", "phi", "sq. error", "PSNR dB");
        for (std::size_t j = 0; j < reference.size(); ++j) {
            const SphericalAngles a = angles_of(reference.directions[j]);
            std::printf("  %5zu %9.3f %9.3f %14.6g %9.2f\n", j, radians_to_degrees(a.theta),
                        radians_to_degrees(a.phi), e.per_direction[j], e.entry_psnr(j));
        }
        if (!opt->out.empty()) std::printf("  wrote %s/errors.csv and %s/error_map.{csv,gp,svg,png}\n",
                                           opt->out.c_str(), opt->out.c_str());
    });
}

// relight fit: a fitted field in CNR relight's layout (relight/fit_file.hpp), the basis given
// or chosen by leave-one-out on the field itself.
void add_fit(CLI::App& relight) {
    auto* cmd = relight.add_subcommand(
        "fit", "Fit a basis to a field and write it as CNR relight's info.json + plane_N.jpg, the files OpenLIME "
               "opens (rfd relight render relights them)");
    struct Options {
        std::string field, basis = "auto", out;
        int planes = relight::FitSpec{}.planes, quality = relight::FitSpec{}.quality,
            resolution = relight::FitSpec{}.resolution;
        double sigma = 0.0;
        bool exact = false, json = false;
        WindowOptions window;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("FIELD", opt->field, "Reflectance field folder or .lp file")->required();
    cmd->add_option("--basis", opt->basis,
                    "ptm (6 functions), hsh2, hsh3 (4, 9; hsh4 with --exact), rbf (radial basis functions over the "
                    "lights, the samples compressed to --planes principal components, as CNR relight's rbf), "
                    "bilinear (the samples resampled on a --resolution grid of directions, blended bilinearly, "
                    "compressed likewise: CNR relight's bilinear), or auto: the one of least leave-one-out error on "
                    "the field, said with every candidate's");
    cmd->add_option("--out", opt->out, "Folder for info.json and the planes")->required();
    cmd->add_option("--planes", opt->planes, "rbf, bilinear: principal components kept (3 per plane file)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--sigma", opt->sigma,
                    "rbf (bilinear: its prior): the Gaussian's width (default: least leave-one-out error)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--resolution", opt->resolution, "bilinear: the side of the grid of directions")
        ->check(CLI::Range(relight::kMinBilinearResolution, relight::kMaxBilinearResolution));
    cmd->add_option("--quality", opt->quality, "JPEG quality of the planes")->check(CLI::Range(1, 100));
    cmd->add_flag("--exact", opt->exact,
                  "rfd's variant: float planes of linear light (plane_N.exr), nothing quantised; OpenLIME does "
                  "not open it");
    add_window_options(*cmd, opt->window);
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        relight::FieldReader field(opt->field, opt->window.window());
        relight::FitSpec spec;
        spec.planes = opt->planes;
        spec.sigma = opt->sigma;
        spec.exact = opt->exact;
        spec.quality = opt->quality;
        spec.resolution = opt->resolution;
        // auto: every candidate judged by leave-one-out in one pass over the field (after one
        // for the widths of rbf and bilinear), by the PSNR RTI users quote for 8-bit captures,
        // linear otherwise.
        nlohmann::json candidates = nlohmann::json::array();
        std::string chosen = opt->basis, why;
        if (opt->basis == "auto") {
            std::vector<std::string> names{"ptm", "hsh2", "hsh3"};
            if (opt->exact) names.emplace_back("hsh4");
            names.emplace_back("rbf");
            names.emplace_back("bilinear");
            std::vector<relight::LightWeights> weights;
            std::vector<std::string> kept;
            std::optional<relight::FieldGram> gram;
            for (const std::string& name : names) {
                relight::LightModel model = relight::parse_light_model(name);
                model.resolution = opt->resolution;
                choose_sigma(model, opt->sigma, field, gram);
                try {
                    weights.emplace_back(model, field.directions());
                    kept.push_back(name);
                } catch (const InputError& error) {
                    candidates.push_back({{"basis", name}, {"refused", error.what()}});
                }
            }
            if (weights.empty()) throw InputError("relight fit: the field's lights carry none of the bases");
            std::vector<const relight::LightWeights*> pointers;
            for (const relight::LightWeights& w : weights) pointers.push_back(&w);
            const std::vector<relight::LeaveOneOut> scores = relight::leave_one_out(field, pointers);
            const bool eight_bit = scores.front().eight_bit();
            double best = -std::numeric_limits<double>::infinity();
            for (std::size_t m = 0; m < scores.size(); ++m) {
                const relight::LeaveOneOut& loo = scores[m];
                const bool all = std::none_of(loo.squared_error.begin(), loo.squared_error.end(),
                                              [](double e) { return std::isnan(e); });
                const double score = eight_bit ? loo.mean_psnr_srgb8() : loo.mean_psnr_linear();
                const relight::LightModel& model = weights[m].model();
                candidates.push_back(
                    {{"basis", kept[m]},
                     {"sigma", model.has_sigma() ? nlohmann::json(model.sigma) : nlohmann::json()},
                     {"mean_psnr_srgb8_db", eight_bit ? finite_or_null(loo.mean_psnr_srgb8()) : nlohmann::json()},
                     {"mean_psnr_linear_db", finite_or_null(loo.mean_psnr_linear())},
                     {"mean_ssim", finite_or_null(loo.mean_ssim())},
                     {"every_light_predicted", all}});
                if (all && score > best) {
                    best = score;
                    chosen = kept[m];
                    spec.sigma = model.sigma;
                }
            }
            if (chosen == "auto") throw InputError("relight fit: no basis predicts every light of the field from the others");
            why = std::string("the greatest mean leave-one-out PSNR (") +
                  (eight_bit ? "8-bit sRGB codes, as RTI tools quote it" : "linear") + ") of the candidates";
        }
        if (chosen == "ptm") {
            spec.type = relight::FitType::Ptm;
            spec.basis = relight::Basis::Ptm;
        } else if (chosen == "hsh2" || chosen == "hsh3" || chosen == "hsh4") {
            spec.type = relight::FitType::Hsh;
            spec.basis = relight::parse_light_model(chosen).basis;
        } else if (chosen == "rbf") {
            spec.type = relight::FitType::Rbf;
        } else if (chosen == "bilinear") {
            spec.type = relight::FitType::Bilinear;
        } else {
            throw InputError("--basis: expected ptm, hsh2, hsh3, hsh4, rbf, bilinear or auto, got '" + opt->basis + "'");
        }
        const relight::FitReport report = relight::fit_field(field, spec, opt->out);
        const relight::FitFile& file = report.file;
        if (opt->json) {
            const nlohmann::json summary = {{"field", opt->field},
                                            {"out", opt->out},
                                            {"basis", chosen},
                                            {"why", why},
                                            {"candidates", candidates},
                                            {"nplanes", file.nplanes},
                                            {"sigma", file.principal() ? nlohmann::json(file.sigma) : nlohmann::json()},
                                            {"resolution", file.type == relight::FitType::Bilinear
                                                               ? nlohmann::json(file.resolution)
                                                               : nlohmann::json()},
                                            {"exact", file.exact},
                                            {"sampled_pixels", report.sampled_pixels},
                                            {"kept_variance", report.kept_variance},
                                            {"clipped_samples", report.clipped}};
            std::printf("%s\n", summary.dump(2).c_str());
            return;
        }
        if (opt->basis == "auto") {
            std::printf("leave-one-out on %s (%zu lights): each light predicted from the others\n", opt->field.c_str(),
                        field.size());
            std::printf("  %-6s %14s %14s %8s\n", "basis", "PSNR sRGB8", "PSNR linear", "SSIM");
            const auto cell = [](const nlohmann::json& v, const char* format) {
                char text[32];
                if (v.is_null()) return std::string("-");
                std::snprintf(text, sizeof text, format, v.get<double>());
                return std::string(text);
            };
            for (const auto& c : candidates) {
                const std::string name = c["basis"];
                if (c.contains("refused")) {
                    std::printf("  %-6s not a candidate: %s\n", name.c_str(), c["refused"].get<std::string>().c_str());
                    continue;
                }
                std::printf("  %-6s %11s dB %11s dB %8s%s\n", name.c_str(), cell(c["mean_psnr_srgb8_db"], "%.2f").c_str(),
                            cell(c["mean_psnr_linear_db"], "%.2f").c_str(), cell(c["mean_ssim"], "%.4f").c_str(),
                            name == chosen ? "   <- chosen" : "");
            }
            std::printf("  chosen: %s, %s\n", chosen.c_str(), why.c_str());
        }
        std::printf("fitted %s to %s (%zu lights, %d x %d) into %s: %d planes in %d %s file(s)\n", chosen.c_str(),
                    opt->field.c_str(), field.size(), file.width, file.height, opt->out.c_str(), file.nplanes,
                    file.jpegs(), file.exact ? "float EXR" : "JPEG");
        if (file.type == relight::FitType::Rbf)
            std::printf("  rbf: sigma %.4g, %d principal components keep %.4f%% of the variance\n", file.sigma,
                        file.nplanes, 100.0 * report.kept_variance);
        if (file.type == relight::FitType::Bilinear)
            std::printf("  bilinear: a %d x %d grid (prior sigma %.4g), %d principal components keep %.4f%% of the "
                        "variance\n",
                        file.resolution, file.resolution, file.sigma, file.nplanes, 100.0 * report.kept_variance);
        if (!file.exact)
            std::printf("  ranges from %zu sampled pixels; %zu plane samples clamped to them (%.3f%%)\n",
                        report.sampled_pixels, report.clipped,
                        100.0 * static_cast<double>(report.clipped) /
                            (static_cast<double>(file.width) * file.height * file.nplanes));
    });
}

}  // namespace

void add_relight_commands(CLI::App& app) {
    CLI::App* relight = app.add_subcommand("relight", "Relight reflectance fields and measure interpolation error")
                            ->require_subcommand(1);
    add_render(*relight);
    add_eval(*relight);
    add_fit(*relight);
    add_implicit_commands(*relight);
    add_upsample_command(*relight);
}

}  // namespace rfd::cli
