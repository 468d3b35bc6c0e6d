// rfd simulate tolerance: how precisely must a Design I/II display be assembled? Sweeps the
// pattern's shift, rotation and pitch error and the spacer's thickness error, charts the
// PSNR of the predicted picture against each, and says how far each may go.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/text.hpp"
#include "core/number.hpp"
#include "core/files.hpp"
#include "core/plot.hpp"
#include "optics/display.hpp"
#include "optics/tolerance.hpp"
#include "predict/summaries.hpp"
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

// How a kind's errors are shown: unit name and factor from the library's value.
struct Display {
    const char* label;
    const char* unit;
    double factor;
    const char* phrase;  // "keep the shift under"
};

Display display_of(optics::MountingError kind) {
    switch (kind) {
        case optics::MountingError::Shift: return {"pattern shift along x", "mm", 1.0, "keep the shift under"};
        case optics::MountingError::Rotation:
            return {"pattern rotation", "deg", 180.0 / std::numbers::pi, "the rotation under"};
        case optics::MountingError::PitchError: return {"pattern pitch error", "ppm", 1e6, "the pitch error under"};
        case optics::MountingError::Spacer: return {"spacer thickness error", "mm", 1.0, "the spacer within"};
    }
    return {"?", "", 1.0, ""};
}

// Four significant digits, but never an exponent: 1.2e+04 ppm reads worse than 12000.
std::string format(double value) { return std::abs(value) >= 1e4 ? format_fixed(value, 0) : format_number(value, 4); }

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
        options.simulation.model = optics::resolve(opt->model, simulator.optics(),
                                                   {pattern.geometry().dot_x, pattern.geometry().dot_y}, opt->tolerance_dots)
                                       .model;
        const std::vector<optics::DisplayLight> lights =
            opt->lights.empty() ? optics::default_tolerance_lights(simulator.optics(), options.simulation.model)
                                : to_display_lights(opt->lights, read_pattern_mapping(opt->pattern), opt->frame);

        const optics::ToleranceReport report = optics::sweep_tolerances(design, pattern, lights, options);

        ensure_directory(opt->out);
        const std::filesystem::path out(opt->out);
        predict::ToleranceSummary record;
        std::ostringstream table;
        std::vector<std::string> phrases;
        for (const optics::ToleranceCurve& curve : report.curves) {
            const Display shown = display_of(curve.kind);
            const std::string name(optics::to_string(curve.kind));
            LineChart chart;
            chart.title = std::string("Tolerance: ") + shown.label + " (" + design.name + ")";
            chart.x_label = std::string(shown.label) + " (" + shown.unit + ", worse of +/-)";
            chart.y_label = "PSNR of the per-lenslet picture (dB)";
            chart.y2_label = "picture shift on the diffuser (lenslets)";
            chart.key_position = "top right";
            PlotSeries psnr{"PSNR vs error-free", {}, {}, false};
            PlotSeries threshold{"threshold " + format(opt->threshold) + " dB", {}, {}, false};
            PlotSeries shift{"picture shift (right axis)", {}, {}, true};
            predict::ToleranceCurveRecord curve_record{name, shown.unit, 0.0, std::nullopt, {}, {}, name + ".svg"};
            for (const optics::TolerancePoint& p : curve.sweep) {
                const double x = p.error * shown.factor;
                psnr.x.push_back(x);
                psnr.y.push_back(p.psnr_db);
                threshold.x.push_back(x);
                threshold.y.push_back(opt->threshold);
                shift.x.push_back(x);
                shift.y.push_back(p.shift_lenslets);
                curve_record.sweep.push_back({x, p.psnr_db, p.shift_lenslets});
            }
            for (const optics::TolerancePoint& p : curve.refinement)
                curve_record.refinement.push_back({p.error * shown.factor, p.psnr_db, std::nullopt});
            chart.series = {psnr, threshold, shift};
            const double largest = curve.sweep.back().error * shown.factor;
            std::string verdict;
            if (curve.tolerance) {
                const double t = *curve.tolerance * shown.factor;
                chart.vertical_markers.push_back({t, "tolerance " + format(t) + " " + shown.unit});
                verdict = format(t) + " " + shown.unit;
            } else {
                verdict = format(largest) + " " + shown.unit + " (the whole sweep stayed above the threshold)";
            }
            write_line_chart(chart, out / name);
            phrases.push_back(std::string(shown.phrase) + " " +
                              (curve.tolerance ? format(*curve.tolerance * shown.factor) + " " + shown.unit
                                               : format(largest) + " " + shown.unit + " (or more)"));
            char row[256];
            std::snprintf(row, sizeof row, "  %-24s %s\n", shown.label, verdict.c_str());
            table << row;
            curve_record.max = largest;
            if (curve.tolerance) curve_record.tolerance = *curve.tolerance * shown.factor;
            record.curves.push_back(std::move(curve_record));
        }
        std::string sentence;
        for (std::size_t k = 0; k < phrases.size(); ++k)
            sentence += (k == 0 ? "" : k + 1 == phrases.size() ? " and " : ", ") + phrases[k];
        if (!sentence.empty()) sentence[0] = static_cast<char>(std::toupper(sentence[0]));
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::ostringstream summary;
        summary << "Assembly tolerances of '" << design.name << "' for " << opt->pattern << " (PSNR >= "
                << format(opt->threshold) << " dB against the error-free prediction, " << lights.size()
                << " light(s), " << optics::to_string(options.simulation.model) << " model):\n"
                << table.str() << sentence << ".\n";
        write_text_file(out / "summary.txt", summary.str());
        record.design = design.name;
        record.threshold_db = opt->threshold;
        record.model = std::string(optics::to_string(options.simulation.model));
        record.lights = lights.size();
        record.nominal_peak = report.nominal_peak;
        record.summary = sentence;
        predict::write_summary(out / "summary.json", record);
        if (opt->json) {
            std::printf("%s", predict::summary_text(record).c_str());
            return;
        }
        std::printf("%s  time %.1f s; charts in %s\n", summary.str().c_str(), seconds, opt->out.c_str());
    });
}

}  // namespace rfd::cli
