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
#include "relight/stage_render.hpp"
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

// Each light's kernel: the command's, or a light file's own radius with the same profile.
std::vector<relight::LightKernel> kernels_of(const Lights& lights, const relight::LightKernel& kernel) {
    std::vector<relight::LightKernel> kernels;
    for (const double radius : lights.radii) {
        relight::LightKernel k = kernel;
        if (radius > 0.0) {
            k.radius = radius;
            if (k.profile == relight::KernelProfile::Gaussian) k.sigma = radius / 3.0;
            if (kernel.is_directional()) k.profile = relight::KernelProfile::Constant;
        }
        kernels.push_back(k);
    }
    return kernels;
}

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
        double dome_radius_mm = 0.0;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("SCENE", opt->scene, "Scene TOML file (docs/formats.md)")->required();
    cmd->add_option("--dome-radius-mm", opt->dome_radius_mm,
                    "Near lamps, as a dome's: each this far from the scene's origin along its direction, of the "
                    "size its kernel subtends from there (default: distant lights)")
        ->check(CLI::PositiveNumber);
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
        relight::Scene scene = relight::load_scene(opt->scene);
        if (seed->count() > 0) scene.seed = opt->seed;
        apply_scene_overrides(scene, opt->resolution, opt->samples);
        const relight::LightKernel kernel =
            opt->kernel.empty() ? scene.kernel : parse_kernel(opt->kernel, scene.kernel);
        if (!opt->kernel.empty() && kernel.radius != scene.kernel.radius)
            scene.shadow_samples = std::max(scene.shadow_samples, relight::default_shadow_samples(kernel));
        const Lights lights = read_lights(opt->lights, scene.seed);

        relight::StageRender run =
            relight::render_field(scene, lights.directions, kernels_of(lights, kernel), opt->out, opt->dome_radius_mm);
        run.kernel = kernel;
        run.light_source = lights.source;
        if (opt->json)
            std::printf("%s\n", relight::stage_render_json(run, scene, opt->scene, opt->out).dump(2).c_str());
        else
            std::fputs(relight::stage_render_text(run, scene, opt->scene, opt->out).c_str(), stdout);
    });
}

}  // namespace rfd::cli
