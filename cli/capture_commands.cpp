// rfd capture render: the virtual light stage, from a scene file to a reflectance field.
// rfd capture pattern: near-uniform light directions for a real or virtual stage.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image_io.hpp"
#include "core/progress.hpp"
#include "core/units.hpp"
#include "relight/field.hpp"
#include "relight/sampling.hpp"
#include "relight/scene.hpp"
#include "relight/stage.hpp"
#include "relight/view_set.hpp"

namespace rfd::cli {
namespace {

relight::LightKernel parse_kernel(const std::string& text, const relight::LightKernel& scene_kernel) {
    if (text == "narrow") return relight::LightKernel::narrow();
    if (text == "wide") return relight::LightKernel::wide();
    std::size_t used = 0;
    double degrees = -1.0;
    try {
        degrees = std::stod(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used != text.size() || !(degrees >= 0.0 && degrees <= 90.0))
        throw InputError("--kernel: expected 'narrow', 'wide' or an angular radius in degrees "
                         "within [0, 90], got '" + text + "'");
    if (degrees == 0.0) return relight::LightKernel::directional();
    const double radius = degrees_to_radians(degrees);
    switch (scene_kernel.profile) {
        case relight::KernelProfile::Smooth: return relight::LightKernel::smooth(radius);
        case relight::KernelProfile::Gaussian: return relight::LightKernel::gaussian(radius / 3.0);
        case relight::KernelProfile::Constant: break;
    }
    return {relight::KernelProfile::Constant, radius, 0.0};
}

struct Lights {
    std::vector<Eigen::Vector3d> directions;
    std::vector<double> radii;  // per light from a light file, 0 = the command's kernel
    std::string source;
};

Lights read_lights(const std::string& text, std::uint64_t seed) {
    Lights lights;
    const bool is_count = !text.empty() && text.find_first_not_of("0123456789") == std::string::npos;
    if (is_count) {
        const unsigned long long count = std::stoull(text);
        if (count < 1 || count > 1000000)
            throw InputError("--lights: expected a count within [1, 1000000] or a .lp file, got " + text);
        lights.directions = relight::repulsion_pattern(count, seed);
        lights.radii.assign(lights.directions.size(), 0.0);
        lights.source = "repulsion pattern of " + text;
        return lights;
    }
    // Neither a count nor an existing file: most likely a mistyped count ("12x", "-5").
    std::error_code ec;
    if (!std::filesystem::is_regular_file(text, ec))
        throw InputError("--lights: expected a count within [1, 1000000] or an existing .lp light "
                         "file, got '" + text + "'");
    for (const auto& entry : relight::read_light_file(text)) {
        lights.directions.push_back(entry.direction);
        lights.radii.push_back(entry.kernel_radius);
    }
    if (lights.directions.empty()) throw InputError(SourceLocation{text}, "the light file lists no light");
    lights.source = text;
    return lights;
}

void add_pattern_command(CLI::App& capture) {
    auto* cmd = capture.add_subcommand(
        "pattern", "Near-uniform light directions on the upper hemisphere by electrostatic repulsion (5.2)");
    struct Options {
        std::size_t count = 0;
        std::uint64_t seed = 1;
        std::string out;
        std::string image_prefix = "img_";
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("--count", opt->count, "Number of directions")->required()->check(CLI::Range(1, 100000));
    cmd->add_option("--seed", opt->seed, "Seed of the starting positions");
    cmd->add_option("--out", opt->out, "Light file to write (.lp)")->required();
    cmd->add_option("--image-prefix", opt->image_prefix,
                    "Image names listed in the light file are PREFIX0000.exr, PREFIX0001.exr...");
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        const auto directions = relight::repulsion_pattern(opt->count, opt->seed);
        std::vector<std::string> files;
        for (std::size_t i = 0; i < directions.size(); ++i) {
            char name[32];
            std::snprintf(name, sizeof name, "%04zu.exr", i);
            files.push_back(opt->image_prefix + name);
        }
        relight::write_light_file(opt->out, files, directions, {});
        const auto nearest = relight::nearest_neighbour_angles(directions);
        double smallest = 0.0, mean = 0.0, lowest = kPi / 2;
        if (directions.size() > 1) {
            smallest = *std::min_element(nearest.begin(), nearest.end());
            for (double a : nearest) mean += a / static_cast<double>(nearest.size());
        }
        for (const auto& d : directions) lowest = std::min(lowest, std::asin(d.z()));
        const double ideal = relight::ideal_spacing(directions.size());
        if (opt->json) {
            const nlohmann::json summary = {
                {"out", opt->out},
                {"count", directions.size()},
                {"seed", opt->seed},
                {"ideal_spacing_deg", radians_to_degrees(ideal)},
                {"nearest_neighbour_min_deg", radians_to_degrees(smallest)},
                {"nearest_neighbour_mean_deg", radians_to_degrees(mean)},
                {"lowest_elevation_deg", radians_to_degrees(lowest)}};
            std::printf("%s\n", summary.dump(2).c_str());
        } else {
            std::printf("wrote %zu direction(s) to %s\n", directions.size(), opt->out.c_str());
            if (directions.size() > 1)
                std::printf("  nearest neighbour  min %.2f deg, mean %.2f deg (hexagonal lattice: %.2f deg)\n",
                            radians_to_degrees(smallest), radians_to_degrees(mean), radians_to_degrees(ideal));
            std::printf("  lowest elevation   %.2f deg above the horizon\n", radians_to_degrees(lowest));
        }
    });
}

}  // namespace

void add_capture_commands(CLI::App& capture) {
    add_pattern_command(capture);
    auto* cmd = capture.add_subcommand(
        "render", "Render a scene under one light at a time into a reflectance field (virtual light stage)");
    struct Options {
        std::string scene;
        std::string lights;
        std::string out;
        std::string kernel;
        std::string resolution;
        std::uint64_t seed = 0;
        int samples = 0;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("SCENE", opt->scene, "Scene TOML file (docs/formats.md)")->required();
    cmd->add_option("--lights", opt->lights,
                    "Light count N (near-uniform upper hemisphere) or a .lp light file")->required();
    cmd->add_option("--out", opt->out, "Output field folder (view_XX/ sub-folders for several cameras)")
        ->required();
    auto* seed = cmd->add_option("--seed", opt->seed, "Seed of the sampling patterns (default: the scene's)");
    cmd->add_option("--kernel", opt->kernel,
                    "Light kernel: narrow (2 deg, constant), wide (15 deg, frost-like), or a radius "
                    "in degrees with the scene's profile (0: directional)");
    cmd->add_option("--resolution", opt->resolution, "Image size WxH (default: the scene's)");
    cmd->add_option("--samples-per-pixel", opt->samples, "Camera rays per pixel (default: the scene's)")
        ->check(CLI::Range(1, 4096));
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt, seed] {
        using Clock = std::chrono::steady_clock;
        relight::Scene scene = relight::load_scene(opt->scene);
        if (seed->count() > 0) scene.seed = opt->seed;
        apply_scene_overrides(scene, opt->resolution, opt->samples);
        const relight::LightKernel kernel =
            opt->kernel.empty() ? scene.kernel : parse_kernel(opt->kernel, scene.kernel);
        if (!opt->kernel.empty() && kernel.radius != scene.kernel.radius)
            scene.shadow_samples = std::max(scene.shadow_samples, relight::default_shadow_samples(kernel));
        const Lights lights = read_lights(opt->lights, scene.seed);

        std::vector<relight::LightKernel> kernels;
        for (const double radius : lights.radii) {
            relight::LightKernel k = kernel;
            if (radius > 0.0) {  // a light file's own kernel radius, with the same profile
                k.radius = radius;
                if (k.profile == relight::KernelProfile::Gaussian) k.sigma = radius / 3.0;
                if (kernel.is_directional()) k.profile = relight::KernelProfile::Constant;
            }
            kernels.push_back(k);
        }

        const std::filesystem::path out(opt->out);
        ensure_directory(out);
        const std::size_t views = scene.cameras.size();
        double camera_seconds = 0.0, light_seconds = 0.0;
        std::size_t shading_points = 0, escaped = 0;
        std::vector<relight::ViewEntry> view_entries;
        // A views file from an earlier run would list views being replaced: written last.
        std::error_code stale;
        std::filesystem::remove(out / "views.txt", stale);
        for (std::size_t v = 0; v < views; ++v) {
            char name[32];
            std::snprintf(name, sizeof name, "view_%02zu", v);
            const std::filesystem::path folder = views == 1 ? out : out / name;
            relight::FieldWriter field(folder);

            const auto t0 = Clock::now();
            const relight::LightStage stage(scene, v);
            const auto t1 = Clock::now();
            camera_seconds += std::chrono::duration<double>(t1 - t0).count();
            shading_points += stage.shading_point_count();
            escaped += stage.escaped_path_count();

            Progress progress(views == 1 ? "lights" : std::string("lights, ") + name, lights.directions.size());
            for (std::size_t i = 0; i < lights.directions.size(); ++i) {
                field.add(stage.render(lights.directions[i], kernels[i]),
                          (stage.to_view_frame() * lights.directions[i]).normalized(), kernels[i].radius);
                progress.advance();
            }
            progress.finish();
            light_seconds += std::chrono::duration<double>(Clock::now() - t1).count();
            field.finish();
            // The view in the display frame (the first camera's field frame): the direction
            // toward this camera from what it looks at, and the rotation back from its
            // light frame.
            const relight::Camera& cam = scene.cameras[v];
            const Eigen::Vector3d toward = scene.cameras.front().field_frame().transpose() *
                                           (cam.position - cam.look_at).normalized();
            view_entries.push_back({name, toward, stage.to_view_frame().transpose(), 0});
        }
        if (views > 1) relight::write_view_file(out / "views.txt", view_entries);

        const double per_light = light_seconds / static_cast<double>(views * lights.directions.size());
        const auto& camera = scene.cameras.front();
        if (opt->json) {
            const nlohmann::json summary = {
                {"scene", opt->scene},
                {"out", opt->out},
                {"views", views},
                {"lights", lights.directions.size()},
                {"light_source", lights.source},
                {"resolution", {camera.width, camera.height}},
                {"samples_per_pixel", scene.samples_per_pixel},
                {"shadow_samples", scene.shadow_samples},
                {"seed", scene.seed},
                {"kernel", {{"profile", relight::to_string(kernel.profile)},
                            {"radius_deg", radians_to_degrees(kernel.radius)},
                            {"directional", kernel.is_directional()}}},
                {"shading_points", shading_points},
                {"escaped_paths", escaped},
                {"camera_paths_seconds", camera_seconds},
                {"seconds_per_light", per_light}};
            std::printf("%s\n", summary.dump(2).c_str());
        } else {
            std::printf("rendered %zu light(s) x %zu view(s) of %s into %s\n", lights.directions.size(),
                        views, opt->scene.c_str(), opt->out.c_str());
            std::printf("  image              %d x %d, %d camera ray(s) per pixel\n", camera.width,
                        camera.height, scene.samples_per_pixel);
            std::printf("  kernel             %s, radius %.3g deg, %d shadow sample(s) per ray\n",
                        kernel.is_directional() ? "directional" : relight::to_string(kernel.profile).c_str(),
                        radians_to_degrees(kernel.radius), scene.shadow_samples);
            std::printf("  cache              %zu shading points, %zu escaped paths\n", shading_points, escaped);
            std::printf("  time               %.3f s camera paths, %.4f s per light\n", camera_seconds, per_light);
        }
    });
}

}  // namespace rfd::cli
