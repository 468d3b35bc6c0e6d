// rfd capture adaptive: adaptive sampling (thesis 5.3) and two-level fields (5.4), driving
// the virtual light stage or a user's rig command.

#include <cstdio>
#include <filesystem>
#include <memory>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/text.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/progress.hpp"
#include "core/units.hpp"
#include "relight/adaptive.hpp"
#include "relight/capture_device.hpp"
#include "relight/field.hpp"
#include "relight/interpolation.hpp"
#include "relight/sampling.hpp"
#include "relight/scene.hpp"
#include "relight/stage_device.hpp"

namespace rfd::cli {
namespace {

struct AdaptiveCommandOptions {
    std::string scene;
    std::string device;
    std::string scratch;
    std::string initial_lights;
    std::string out;
    std::string resolution;
    WindowOptions window;
    int samples = 0;
    std::size_t initial = 256;
    std::size_t per_iteration = 16;
    std::size_t total = 1024;
    double min_separation_deg = 2.0;
    double two_level_deg = 0.0;
    double narrow_radius_deg = 0.0;
    double wide_radius_deg = 0.0;
    std::uint64_t seed = 1;
    bool json = false;
};

std::vector<Eigen::Vector3d> initial_directions(const AdaptiveCommandOptions& opt) {
    if (opt.initial_lights.empty()) return relight::repulsion_pattern(opt.initial, opt.seed);
    std::vector<Eigen::Vector3d> directions;
    for (const auto& entry : relight::read_light_file(opt.initial_lights)) directions.push_back(entry.direction);
    if (directions.size() < 3)
        throw InputError(SourceLocation{opt.initial_lights},
                         "adaptive sampling needs at least 3 initial directions to triangulate, the file lists " +
                             std::to_string(directions.size()));
    return directions;
}

std::unique_ptr<relight::CaptureDevice> make_device(const AdaptiveCommandOptions& opt) {
    if (!opt.scene.empty()) {
        if (!opt.window.region.empty() || opt.window.scale != 1.0)
            throw InputError("--region and --scale apply to a rig's photographs (--device); a scene renders what "
                             "its camera sees (set its camera and --resolution)");
        relight::Scene scene = relight::load_scene(opt.scene);
        apply_scene_overrides(scene, opt.resolution, opt.samples);
        return std::make_unique<relight::StageCaptureDevice>(std::move(scene));
    }
    const std::filesystem::path scratch =
        opt.scratch.empty() ? std::filesystem::path(opt.out) / "capture" : std::filesystem::path(opt.scratch);
    return std::make_unique<relight::CommandCaptureDevice>(opt.device, scratch,
                                                           degrees_to_radians(opt.narrow_radius_deg),
                                                           degrees_to_radians(opt.wide_radius_deg),
                                                           opt.window.window());
}

CsvTable iterations_csv(const relight::AdaptiveRun& run) {
    CsvTable table({"iteration", "images", "analysis_seconds"});
    for (std::size_t k = 0; k < run.images_after.size(); ++k) {
        const double seconds = k == 0 ? 0.0 : run.analysis_seconds[k - 1];
        table.add_row({std::to_string(k), std::to_string(run.images_after[k]), format_fixed(seconds, 6)});
    }
    return table;
}

}  // namespace

void add_adaptive_command(CLI::App& capture) {
    auto* cmd = capture.add_subcommand(
        "adaptive", "Adaptive sampling (thesis 5.3): capture where the field changes, optionally two-level (5.4)");
    auto opt = std::make_shared<AdaptiveCommandOptions>();
    cmd->add_option("SCENE", opt->scene, "Scene TOML file for the virtual light stage");
    cmd->add_option("--resolution", opt->resolution, "Scene: image size WxH (default: the scene's)");
    cmd->add_option("--samples-per-pixel", opt->samples, "Scene: camera rays per pixel (default: the scene's)")
        ->check(CLI::Range(1, 4096));
    cmd->add_option("--device", opt->device,
                    "Rig command instead of a scene; placeholders {x} {y} {z} {theta} {phi} {kernel} {out}");
    add_window_options(*cmd, opt->window);
    cmd->add_option("--scratch", opt->scratch, "Folder for the rig command's images (default: OUT/capture)");
    cmd->add_option("--narrow-radius", opt->narrow_radius_deg, "Rig: angular radius of its narrow light, degrees")
        ->check(CLI::Range(0.0, 90.0));
    cmd->add_option("--wide-radius", opt->wide_radius_deg, "Rig: angular radius of its wide light, degrees")
        ->check(CLI::Range(0.0, 90.0));
    cmd->add_option("--initial", opt->initial, "Initial directions, near-uniform by repulsion")
        ->check(CLI::Range(std::size_t{3}, std::size_t{100000}));
    cmd->add_option("--initial-lights", opt->initial_lights, "Initial directions from a .lp file instead");
    cmd->add_option("--per-iteration", opt->per_iteration, "Directions inserted per iteration, m")
        ->check(CLI::Range(std::size_t{1}, std::size_t{100000}));
    cmd->add_option("--total", opt->total, "Stop at this many images")
        ->check(CLI::Range(std::size_t{3}, std::size_t{1000000}));
    cmd->add_option("--min-separation", opt->min_separation_deg,
                    "Density limit: no two directions closer, degrees")
        ->check(CLI::Range(0.01, 45.0));
    cmd->add_option("--two-level", opt->two_level_deg,
                    "Re-capture initial directions whose neighbours are all farther than this many "
                    "degrees with the wide light (thesis: 9)")
        ->check(CLI::Range(0.0, 90.0));
    cmd->add_option("--seed", opt->seed, "Seed of the initial pattern");
    cmd->add_option("--out", opt->out, "Output field folder")->required();
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        if (opt->scene.empty() == opt->device.empty())
            throw InputError("rfd capture adaptive: give either a SCENE file (virtual light stage) or --device "
                             "COMMAND (a real rig), not both or neither");
        const std::vector<Eigen::Vector3d> initial = initial_directions(*opt);
        if (initial.size() > opt->total)
            throw InputError("--total " + std::to_string(opt->total) + " is below the " +
                             std::to_string(initial.size()) + " initial directions");
        std::unique_ptr<relight::CaptureDevice> device = make_device(*opt);

        relight::AdaptiveOptions options;
        options.per_iteration = opt->per_iteration;
        options.total = opt->total;
        options.min_separation = degrees_to_radians(opt->min_separation_deg);
        Progress progress("adaptive capture", opt->total);
        std::size_t shown = 0;
        const relight::AdaptiveRun run =
            relight::adaptive_capture(*device, initial, relight::delaunay_triangles, options,
                                      [&](const relight::AdaptiveRun& state) {
                                          progress.advance(state.field.size() - shown);
                                          shown = state.field.size();
                                      });
        progress.finish();
        relight::ReflectanceField field = run.field;
        std::vector<std::size_t> replaced;
        if (opt->two_level_deg > 0.0)
            replaced = relight::make_two_level(field, initial.size(), *device, relight::delaunay_triangles,
                                               degrees_to_radians(opt->two_level_deg));
        if (field.kernel_radii.empty() && device->kernel_radius(relight::KernelChoice::Narrow) > 0.0)
            field.kernel_radii.assign(field.size(), device->kernel_radius(relight::KernelChoice::Narrow));

        const std::filesystem::path out(opt->out);
        relight::write_field(out, field);
        iterations_csv(run).write(out / "adaptive.csv");

        const double analysis = std::accumulate(run.analysis_seconds.begin(), run.analysis_seconds.end(), 0.0);
        const double per_image = analysis / static_cast<double>(std::max<std::size_t>(field.size(), 1));
        if (opt->json) {
            const nlohmann::json summary = {{"out", opt->out},
                                            {"images", field.size()},
                                            {"initial", initial.size()},
                                            {"iterations", run.analysis_seconds.size()},
                                            {"density_limit_reached", run.density_limit_reached},
                                            {"wide_replaced", replaced.size()},
                                            {"analysis_seconds", analysis},
                                            {"analysis_seconds_per_image", per_image}};
            std::printf("%s\n", summary.dump(2).c_str());
        } else {
            std::printf("adaptive field of %zu images in %s (%zu initial, %zu iterations)\n", field.size(),
                        opt->out.c_str(), initial.size(), run.analysis_seconds.size());
            if (run.density_limit_reached)
                std::printf("  stopped at the density limit (%.3g deg) before the budget\n", opt->min_separation_deg);
            if (opt->two_level_deg > 0.0)
                std::printf("  two-level: %zu initial directions re-captured with the wide light\n", replaced.size());
            std::printf("  analysis           %.3f s in all, %.2f ms per image\n", analysis, 1e3 * per_image);
        }
    });
}

}  // namespace rfd::cli
