// rfd simulate tolerance: how precisely must a Design I/II display be assembled? Sweeps the
// pattern's shift, rotation and pitch error and the spacer's thickness error, charts the
// PSNR of the predicted picture against each, and says how far each may go.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/number.hpp"
#include "optics/diffraction.hpp"
#include "optics/display.hpp"
#include "optics/tolerance.hpp"
#include "predict/summaries.hpp"
#include "predict/tolerance_report.hpp"
#include "patterns/encode.hpp"
#include "print/printed.hpp"

namespace rfd::cli {
namespace {

// --pitch-error: "500ppm", "0.05%" or a bare number of ppm; relative value.
double parse_pitch_error(const std::string& text) {
    std::string number = text;
    double unit = 1e-6;
    auto ends_with = [&](const std::string& suffix) {
        return number.size() > suffix.size() && number.compare(number.size() - suffix.size(), suffix.size(), suffix) == 0;
    };
    if (ends_with("ppm")) {
        number.resize(number.size() - 3);
    } else if (ends_with("%")) {
        number.resize(number.size() - 1);
        unit = 1e-2;
    }
    const double value = finite_number(number).value_or(-1.0);
    if (value < 0.0)
        throw InputError(SourceLocation{"", 0, 0, "--pitch-error"},
                         "expected a number >= 0 in ppm ('500', '500ppm') or percent ('0.05%'), got '" + text + "'");
    return value * unit;
}

}  // namespace

void add_simulate_tolerance_command(CLI::App& simulate) {
    auto* cmd = simulate.add_subcommand(
        "tolerance", "How precisely to assemble a Design I/II display: PSNR of the predicted picture (one value per "
                     "lenslet) against pattern shift, rotation, pitch error and spacer error, and the largest error "
                     "of each that keeps it above a threshold");
    struct Options {
        PrintOptions print;
        std::string design, pattern, out, pitch_error;
        optics::ModelChoice model = optics::ModelChoice::Paraxial;
        std::vector<std::string> lights;
        predict::LightFrame frame{};
        std::optional<double> shift_mm, rotation_deg, spacer_mm;
        double threshold = 30.0, tolerance_dots = 0;  // add_option and add_frame_option set the defaults
        int steps = 6, refinements = 4, rays = 0;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->design, "Design TOML file (Design I or II)")->required();
    cmd->add_option("PATTERN", opt->pattern, "Pattern file from `rfd pattern encode`")->required();
    cmd->add_option("--out", opt->out, "Output folder: a chart per error kind (CSV, .gp, SVG, PNG), summary.txt and summary.json")
        ->required();
    cmd->add_option("--light", opt->lights,
                    std::string("A distant light, in the frame --frame names ") + kLightSyntax +
                        "; repeat for several; each is compared on its own. Default: the axis and two "
                        "directions at half the wrap-over angle (along x and y)");
    add_frame_option(*cmd, opt->frame);
    cmd->add_option("--shift", opt->shift_mm, "Largest pattern shift along x, mm (default: half a lenslet pitch; 0 skips)");
    cmd->add_option("--rotation", opt->rotation_deg,
                    "Largest pattern rotation about the array's axis, degrees (default: half a pitch at the "
                    "outermost lenslet; 0 skips)");
    cmd->add_option("--pitch-error", opt->pitch_error,
                    "Largest pitch error of the print, ppm ('500', '500ppm') or percent ('0.05%') (default: half "
                    "a pitch at the outermost lenslet; 0 skips)");
    cmd->add_option("--spacer", opt->spacer_mm,
                    "Largest error of the pattern-to-diffuser distance, mm (default: a quarter of it; 0 skips)");
    cmd->add_option("--steps", opt->steps, "Sweep values after zero");
    cmd->add_option("--refinements", opt->refinements, "Bisection steps at the threshold crossing");
    cmd->add_option("--threshold", opt->threshold, "PSNR threshold, dB");
    // Paraxial by default: a tolerance compares two predictions of one model, so the
    // model's own error (a few print dots for Design I) largely cancels, at a fifth of the time.
    add_model_option(*cmd, opt->model);
    add_option(*cmd, optics::kModelToleranceOption, opt->tolerance_dots);
    add_print_options(*cmd, opt->print);
    add_option(*cmd, optics::kRaysPerSideOption, opt->rays);
    cmd->add_flag("--json", opt->json, "Machine-readable summary");
    cmd->callback([opt] {
        const auto start = std::chrono::steady_clock::now();
        const optics::Design design = optics::load_design(opt->design);
        const optics::DisplaySimulator simulator(design);
        const print::PrintedTransparency pattern = printed_pattern(design, opt->pattern, opt->print);

        optics::ToleranceOptions options = optics::default_tolerance_ranges(simulator.optics());
        if (opt->shift_mm) options.max_shift_mm = *opt->shift_mm;
        if (opt->rotation_deg) options.max_rotation_rad = *opt->rotation_deg * std::numbers::pi / 180.0;
        if (!opt->pitch_error.empty()) options.max_pitch_error = parse_pitch_error(opt->pitch_error);
        if (opt->spacer_mm) options.max_spacer_mm = *opt->spacer_mm;
        options.steps = opt->steps;
        options.refinements = opt->refinements;
        options.threshold_db = opt->threshold;
        options.simulation.rays_per_side = opt->rays;
        const optics::ResolvedModel choice = optics::resolve(
            opt->model, simulator.optics(), {pattern.geometry().dot_x, pattern.geometry().dot_y}, opt->tolerance_dots);
        options.simulation.model = choice.model;
        const std::unique_ptr<optics::Transparency> through =
            choice.diffraction ? optics::diffracted(pattern, simulator.optics()) : nullptr;
        const std::vector<optics::DisplayLight> lights =
            opt->lights.empty() ? optics::default_tolerance_lights(simulator.optics(), options.simulation.model)
                                : to_display_lights(opt->lights, read_pattern_mapping(opt->pattern), opt->frame);

        const optics::ToleranceReport report = optics::sweep_tolerances(
            design, through ? *through : static_cast<const optics::Transparency&>(pattern), lights, options);
        const predict::ToleranceReportText written = predict::write_tolerance_report(
            opt->out, report,
            {design.name, opt->pattern, opt->threshold, std::string(optics::to_string(options.simulation.model)),
             lights.size()});
        if (opt->json) {
            std::printf("%s", predict::summary_text(written.summary).c_str());
            return;
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("%s  time %.1f s; charts in %s\n", written.text.c_str(), seconds, opt->out.c_str());
    });
}

}  // namespace rfd::cli
