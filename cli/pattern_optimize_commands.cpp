// rfd pattern optimize: a Design I/II pattern chosen through the display's own forward
// model, starting from the direct encoding (predict/pattern_optimization.hpp).

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "optics/display.hpp"
#include "predict/compare.hpp"
#include "predict/optimize.hpp"
#include "predict/pattern_optimization.hpp"
#include "print/printed.hpp"

namespace rfd::cli {
namespace {

// --crop I,J,W,H: whole lenslets, from the bottom-left lenslet of the array.
predict::LensletWindow parse_crop(const std::string& text, const optics::Lattice& lattice) {
    int i = 0, j = 0, w = 0, h = 0;
    char tail = 0;
    if (std::sscanf(text.c_str(), "%d,%d,%d,%d%c", &i, &j, &w, &h, &tail) != 4 || i < 0 || j < 0 || w < 1 || h < 1 ||
        i + w > lattice.count_x() || j + h > lattice.count_y())
        throw InputError("--crop: expected I,J,W,H, whole lenslets inside the " + std::to_string(lattice.count_x()) +
                         " x " + std::to_string(lattice.count_y()) + " array, got '" + text + "'");
    return {i, j, i + w, j + h};
}

}  // namespace

void add_pattern_optimize_command(CLI::App& pattern) {
    auto* cmd = pattern.add_subcommand(
        "optimize", "Choose a Design I/II pattern through the display's own forward model: the printable pattern whose "
                    "predicted output comes closest to the field relit in software, over the field of view");
    struct Options {
        std::string design, field, from, out, report, crop, lights = "sweep";
        PrintOptions print;
        optics::ModelChoice model = optics::ModelChoice::Auto;
        double spacing = 0, stop_fraction = 0, core_weight = 0;  // add_option sets the defaults
        int iterations = 0, rays = 0, chart_every = 5, judge_sweep = static_cast<int>(predict::kSweepOption.fallback);
        bool unbounded = false, json = false, timings = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->design, "Design TOML file (Design I or II)")->required();
    cmd->add_option("FIELD", opt->field, "The reflectance field (folder or .lp) the --from pattern was encoded from")
        ->required();
    cmd->add_option("--from", opt->from,
                    "The direct encoding (`rfd pattern encode`): its encoder's options, white and printer are kept, "
                    "its values are the start")
        ->required();
    cmd->add_option("--out", opt->out, "Optimised pattern file (.exr)")->required();
    cmd->add_option("--lights", opt->lights,
                    "The light directions to fit: sweep (the default: one per node inside a lenslet's cell, each "
                    "weighted by the solid angle it stands for) or a light file (.lp, the field's frame: the lights "
                    "the display will meet, equally weighted; those outside its field of view are left out)");
    add_option(*cmd, predict::kNodeSpacingOption, opt->spacing);
    add_option(*cmd, predict::kIterationsOption, opt->iterations);
    add_option(*cmd, predict::kStopFractionOption, opt->stop_fraction);
    add_option(*cmd, predict::kOptimizeRaysOption, opt->rays);
    add_option(*cmd, predict::kCoreWeightOption, opt->core_weight);
    add_model_option(*cmd, opt->model);
    add_print_options(*cmd, opt->print);
    cmd->add_option("--crop", opt->crop,
                    "Only fit the cells of lenslets I,J,W,H (from the bottom-left lenslet): a quick trial");
    cmd->add_flag("--unbounded", opt->unbounded,
                  "Drop the printer's bounds (CGLS): the unconstrained optimum, the ceiling; not printable as is");
    cmd->add_option("--report", opt->report,
                    "Also write a folder with the objective and the held-out PSNR against iterations");
    cmd->add_flag("--timings", opt->timings,
                  "With --report: chart against the solver's time, and add its seconds to iterations.csv (a report "
                  "with timings differs from run to run)");
    cmd->add_option("--judge-sweep", opt->judge_sweep,
                    "With --report: the simulator's judgement of the direct and the optimised pattern over this many "
                    "light directions (0: none)")
        ->check(CLI::Range(0, 1000));
    cmd->add_option("--chart-every", opt->chart_every, "Held-out PSNR every this many iterations")
        ->check(CLI::Range(1, 100000));
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        const optics::Design design = optics::load_design(opt->design);
        const optics::DisplaySimulator simulator(design);
        const print::PrintedTransparency direct = printed_pattern(design, opt->from, opt->print);
        const predict::EncodedField reference(design, opt->from, direct.geometry(), direct.tone().white, opt->field);
        predict::PatternOptimizationSettings settings;
        settings.from = opt->from;
        settings.lights = opt->lights;
        settings.spacing_mm = opt->spacing;
        settings.stop_fraction = opt->stop_fraction;
        settings.core_weight = opt->core_weight;
        settings.iterations = opt->iterations;
        settings.rays_per_side = opt->rays;
        settings.chart_every = opt->chart_every;
        settings.model = opt->model;
        settings.unbounded = opt->unbounded;
        if (!opt->crop.empty()) settings.crop = parse_crop(opt->crop, reference.encoder().lattice());
        settings.crop_text = opt->crop;

        const predict::PatternOptimization run =
            predict::optimize_pattern(simulator, direct, reference.encoder(), settings);
        predict::write_optimized_pattern(opt->out, run, settings, direct.tone());
        std::vector<predict::JudgedDirection> judged;
        if (!opt->report.empty()) {
            if (opt->judge_sweep > 0) {
                const print::PrintedTransparency optimized = printed_pattern(design, opt->out, opt->print);
                judged = predict::judge_patterns(simulator, direct, optimized, reference.encoder(), opt->judge_sweep);
            }
            predict::write_optimization_report(opt->report, design.name, run, judged, opt->timings);
        }
        if (opt->json)
            std::printf("%s\n", predict::optimization_json(run, settings, opt->out, judged).dump(2).c_str());
        else
            std::fputs(predict::optimization_text(run, settings, opt->out, judged).c_str(), stdout);
    });
}

}  // namespace rfd::cli
