// rfd simulate compare: the predicted display output beside the software relighting of the
// same field at the display's resolution (predict/compare.hpp), for a sweep of light
// directions; and the simulator's speed-versus-accuracy chart.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "predict/compare_angular.hpp"
#include "optics/display_angular.hpp"
#include "core/units.hpp"
#include "core/text.hpp"
#include "core/progress.hpp"
#include "core/files.hpp"
#include "core/csv.hpp"
#include "optics/diffraction.hpp"
#include "optics/display.hpp"
#include "predict/compare.hpp"
#include "predict/compare_report.hpp"
#include "predict/display_lights.hpp"
#include "predict/summaries.hpp"
#include "patterns/encode.hpp"
#include "print/printed.hpp"

namespace rfd::cli {
namespace {

std::vector<int> parse_ray_counts(const std::string& text) {
    std::vector<int> counts;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        std::size_t used = 0;
        int value = 0;
        try {
            value = std::stoi(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used != item.size() || value < 1 || value > 256)
            throw InputError("--accuracy-rays: expected ray counts per side in [1, 256] separated by commas, got '" +
                             text + "'");
        counts.push_back(value);
    }
    if (counts.empty()) throw InputError("--accuracy-rays: expected at least one ray count");
    return counts;
}

// --models for --chart-accuracy: each named model as it resolves on this design
// ("auto (exact)").
std::vector<predict::AccuracyModel> parse_models(const std::string& text, const optics::DesignOptics& optics,
                                                 const Eigen::Vector2d& dot_mm, double tolerance_dots) {
    std::vector<predict::AccuracyModel> models;
    std::stringstream in(text);
    std::string name;
    while (std::getline(in, name, ',')) {
        const optics::ModelChoice asked = value_of(optics::kModelChoiceNames, name, SourceLocation{"", 0, 0, "--models"});
        const optics::Model model = optics::resolve(asked, optics, dot_mm, tolerance_dots).model;
        models.push_back(
            {asked == optics::ModelChoice::Auto ? "auto (" + std::string(optics::to_string(model)) + ")" : name, model});
    }
    if (models.empty()) throw InputError("--models: expected at least one model");
    return models;
}

// --light: white point lights, compared in the field's frame (a display-frame light is the
// field light it shows).
std::vector<Eigen::Vector3d> white_light_directions(const std::vector<std::string>& texts, predict::LightFrame frame,
                                                    const patterns::AngularMapping& mapping) {
    std::vector<Eigen::Vector3d> directions;
    for (const std::string& text : texts) {
        const relight::Light named = parse_light(text);
        const auto* point = std::get_if<relight::DirectionalLight>(&named);
        if (!point || point->irradiance != Eigen::Vector3d::Ones())
            throw InputError("--light " + text + ": compare takes point lights of white light (THETA,PHI)");
        const relight::Light light = predict::light_in_field_frame(named, frame, mapping);
        directions.push_back(std::get<relight::DirectionalLight>(light).direction.normalized());
    }
    return directions;
}


// Designs III and IV: the display from a grid of viewpoints under a grid of lights against
// the 6D field relit and viewed the same way (predict/compare_angular.hpp).
struct AngularCompareOptions {
    std::string design, pattern, field, out;
    AngularSource source;
    PrintOptions print;
    optics::ModelChoice model = optics::ModelChoice::Auto;
    double tolerance_dots = 0.0;
    int light_grid = 5, view_grid = 3, lens_rays = 0;
    bool held_out = false, json = false;
};

void run_angular_compare(const optics::Design& design, AngularCompareOptions o) {
    const auto start = std::chrono::steady_clock::now();
    const optics::AngularDisplaySimulator simulator(design);
    const print::PrintedTransparency pattern = printed_pattern(design, o.pattern, o.print);
    const optics::ResolvedModel choice =
        optics::resolve(o.model, simulator.optics(), simulator.optics().dot_mm(), o.tolerance_dots);
    const std::unique_ptr<optics::Transparency> through =
        choice.diffraction ? optics::diffracted(pattern, simulator.optics()) : nullptr;
    o.source.path = o.field;
    if (o.source.path.empty() == o.source.procedural.empty())
        throw InputError("Designs III and IV: give FIELD (the view set or field the pattern was encoded from) or "
                         "--procedural letters|diamonds, as `pattern encode-angular` was given");
    const std::unique_ptr<patterns::AngularField> field = angular_field(o.source, simulator.meso(), choice.model);
    const std::vector<Eigen::Vector3d> lights = predict::angular_light_grid(simulator, o.light_grid, o.held_out);
    const std::vector<Eigen::Vector3d> views = predict::angular_view_grid(simulator, o.view_grid, o.held_out);
    optics::AngularSimulationOptions options;
    options.model = choice.model;
    if (o.lens_rays > 0) options.rays_per_side = o.lens_rays;
    const predict::AngularComparison comparison(
        simulator, through ? *through : static_cast<const optics::Transparency&>(pattern), *field, lights,
        pattern.tone(), options);
    std::vector<predict::PairComparison> pairs;
    Progress progress("comparing", lights.size());
    for (std::size_t light = 0; light < lights.size(); ++light) {
        for (predict::PairComparison& pair : comparison.compare(light, views)) pairs.push_back(std::move(pair));
        progress.advance();
    }
    progress.finish();
    double peak = 0.0;
    for (const auto& pair : pairs) peak = std::max(peak, pair.comparison.peak);
    const auto angles = [](const Eigen::Vector3d& d) {
        return std::pair{radians_to_degrees(std::acos(std::clamp(d.z(), -1.0, 1.0))),
                         radians_to_degrees(std::atan2(d.y(), d.x()))};
    };
    CsvTable table({"light_theta_deg", "light_phi_deg", "view_theta_deg", "view_phi_deg", "psnr_db",
                    "psnr_own_peak_db", "mse", "peak", "bins_bound_psnr_db", "crossed_fraction"});
    // The headline pools the squared errors of every pair (a pair the field leaves dark, and
    // the display too, would read as a perfect 100 dB and flatter a mean of PSNRs).
    double mse_sum = 0.0, ceiling_sum = 0.0, lowest = 1e300;
    for (const auto& pair : pairs) {
        const double psnr = predict::psnr_against_field_db(pair.comparison.mse, peak).value_or(0.0);
        mse_sum += pair.comparison.mse;
        ceiling_sum += pair.ceiling_comparison.mse;
        lowest = std::min(lowest, psnr);
        const auto [lt, lp] = angles(pair.light);
        const auto [vt, vp] = angles(pair.view);
        table.add_row({format_fixed(lt, 4), format_fixed(lp, 4), format_fixed(vt, 4), format_fixed(vp, 4),
                       format_fixed(psnr, 4), format_fixed(pair.comparison.psnr_db, 4),
                       format_number(pair.comparison.mse, 9), format_number(pair.comparison.peak, 9),
                       format_fixed(predict::psnr_against_field_db(pair.ceiling_comparison.mse, peak).value_or(0.0), 4),
                       format_fixed(pair.crossed_fraction, 6)});
    }
    const double count = pairs.empty() ? 1.0 : static_cast<double>(pairs.size());
    const double mean = predict::psnr_against_field_db(mse_sum / count, peak).value_or(0.0);
    const double ceiling = predict::psnr_against_field_db(ceiling_sum / count, peak).value_or(0.0);
    ensure_directory(o.out);
    table.write(std::filesystem::path(o.out) / "pairs.csv");
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const nlohmann::json summary{{"design", design.name},
                                 {"pattern", o.pattern},
                                 {"field", o.field.empty() ? "procedural " + o.source.procedural : o.field},
                                 {"model", std::string(optics::to_string(choice.model))},
                                 {"diffraction", choice.diffraction},
                                 {"lights", lights.size()},
                                 {"views", views.size()},
                                 {"held_out", o.held_out},
                                 {"pairs", pairs.size()},
                                 {"field_peak", peak},
                                 {"psnr_db", mean},
                                 {"bins_bound_psnr_db", ceiling},
                                 {"psnr_min_db", pairs.empty() ? 0.0 : lowest}};
    write_text_file(std::filesystem::path(o.out) / "summary.json", summary.dump(2) + "\n");
    if (o.json) {
        std::printf("%s\n", summary.dump(2).c_str());
        return;
    }
    std::printf("%s: %s seen from %zu viewpoints under %zu lights%s (%s optics%s)\n", o.out.c_str(),
                design.name.c_str(), views.size(), lights.size(), o.held_out ? ", the held-out grids" : "",
                std::string(optics::to_string(choice.model)).c_str(), choice.diffraction ? " and diffraction" : "");
    std::printf("  PSNR         %.2f dB over %zu pairs' macro-pixels, the worst pair %.2f dB (against the brightest "
                "reference)\n",
                mean, pairs.size(), pairs.empty() ? 0.0 : lowest);
    std::printf("  bins' bound  %.2f dB: one value per incident bin, the bin's mean of the field (crosstalk aside: an "
                "upper bound on any pattern)\n",
                ceiling);
    std::printf("  pairs        %s/pairs.csv\n", o.out.c_str());
    std::printf("  time         %.2f s\n", seconds);
}

}  // namespace

void add_simulate_compare_command(CLI::App& simulate) {
    auto* cmd = simulate.add_subcommand(
        "compare", "Predicted display output beside the software relighting of the same field, at the display's "
                   "resolution, with PSNR and error maps, for a sweep of light directions (Designs I and II)");
    struct Options {
        PrintOptions print;
        std::string design, pattern, field, out, encoded_for, models = "paraxial,exact,auto",
                                                          accuracy_rays = "2,4,8,16";
        optics::ModelChoice model = optics::ModelChoice::Auto;
        std::vector<std::string> lights;
        predict::LightFrame frame{};
        double pixels_per_lenslet = 16.0;
        int sweep = 0, rays = 0, reference_rays = 32, view_pixels = 0;  // add_option sets sweep's default
        double tolerance_dots = 0, error_gain = 4.0;
        bool json = false, chart_accuracy = false;
        AngularCompareOptions angular;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->design, "Design TOML file")->required();
    cmd->add_option("PATTERN", opt->pattern, "Pattern file from `rfd pattern encode` (or encode-angular)")->required();
    cmd->add_option("FIELD", opt->field,
                    "The reflectance field the pattern was encoded from (folder or .lp; Designs III/IV: the view set, "
                    "or --procedural)");
    cmd->add_option("--out", opt->out, "Output folder")->required();
    cmd->add_option("--encoded-for", opt->encoded_for,
                    "The design the pattern was encoded and printed for, when DESIGN is another (the array's measured "
                    "pitch: rfd calibrate pitch): that print laid centred on DESIGN's array, against the field as "
                    "DESIGN's lenslets show it");
    cmd->add_option("--light", opt->lights,
                    "Also compare under a white light from THETA,PHI (degrees, in the frame --frame names); repeat "
                    "for several");
    add_frame_option(*cmd, opt->frame);
    add_option(*cmd, predict::kSweepOption, opt->sweep);
    add_model_option(*cmd, opt->model);
    add_option(*cmd, optics::kModelToleranceOption, opt->tolerance_dots);
    cmd->add_option("--rays-per-side,--rays", opt->rays,
                    "Rays per side of each lenslet's grid, per light direction (default: 32 where macro-pixel cores "
                    "are compared, Design II; else as simulate's)")
        ->check(CLI::Range(optics::kRaysPerSideOption.min, optics::kRaysPerSideOption.max));
    cmd->add_option("--pixels-per-lenslet", opt->pixels_per_lenslet,
                    "Diffuser pixels per lenslet pitch in the simulation")
        ->check(CLI::Range(4.0, 64.0));
    add_print_options(*cmd, opt->print);
    cmd->add_option("--view-pixels", opt->view_pixels,
                    "Pixels per lenslet in the side-by-side PNGs (default: about 240 pixels per panel)")
        ->check(CLI::Range(0, 256));
    cmd->add_option("--error-gain", opt->error_gain, "Error panel of the PNGs: |error| times this")
        ->check(positive_number());
    cmd->add_flag("--chart-accuracy", opt->chart_accuracy,
                  "Also the speed-versus-accuracy chart: each of --models at each of --accuracy-rays against a "
                  "converged exact prediction (--reference-rays), simulation time measured in the same run");
    cmd->add_option("--models", opt->models, "Models for --chart-accuracy");
    cmd->add_option("--accuracy-rays", opt->accuracy_rays, "Rays per side for --chart-accuracy");
    cmd->add_option("--reference-rays", opt->reference_rays, "Rays per side of the converged prediction")
        ->check(CLI::Range(1, 512));
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout (also written to OUT/summary.json)");
    add_angular_source_options(*cmd, opt->angular.source);
    cmd->add_option("--light-grid", opt->angular.light_grid,
                    "Designs III/IV: lights per side of the grid over the meso array")
        ->check(CLI::Range(2, 64));
    cmd->add_option("--view-grid", opt->angular.view_grid,
                    "Designs III/IV: viewpoints per side of the grid over the output cone")
        ->check(CLI::Range(2, 64));
    cmd->add_flag("--held-out", opt->angular.held_out,
                  "Designs III/IV: the grids' midpoints instead (lights and viewpoints between the grid's)");
    add_option(*cmd, optics::kLensRaysOption, opt->angular.lens_rays);
    cmd->callback([opt] {
        const auto start = std::chrono::steady_clock::now();
        const optics::Design design = optics::load_design(opt->design);
        if (optics::is_observer_variant(design.kind)) {
            AngularCompareOptions angular = opt->angular;
            angular.design = opt->design;
            angular.pattern = opt->pattern;
            angular.field = opt->field;
            angular.out = opt->out;
            angular.print = opt->print;
            angular.model = opt->model;
            angular.tolerance_dots = opt->tolerance_dots;
            angular.json = opt->json;
            run_angular_compare(design, angular);
            return;
        }
        if (opt->field.empty()) throw InputError("FIELD: the reflectance field the pattern was encoded from");
        const AngularSource& a = opt->angular.source;
        if (!a.procedural.empty() || !a.window.region.empty() || a.window.scale != 1.0 || a.coverage != 1.0)
            throw InputError("--procedural, --region, --scale and --coverage are for Designs III and IV; Designs I and II "
                             "read the field as the pattern records it");
        const optics::DisplaySimulator simulator(design);
        const optics::Design printed_for = opt->encoded_for.empty() ? design : optics::load_design(opt->encoded_for);
        if (printed_for.kind != design.kind)
            throw InputError(SourceLocation{opt->encoded_for, 0, 0, "--encoded-for"},
                             "a design of another kind than DESIGN's: its print does not fit DESIGN's array");
        const print::PrintedTransparency pattern = printed_pattern(printed_for, opt->pattern, opt->print);
        if (opt->sweep == 0 && opt->lights.empty()) throw InputError("--sweep 0 needs at least one --light");
        const Eigen::Vector2d dot_mm(pattern.geometry().dot_x, pattern.geometry().dot_y);
        const optics::ResolvedModel choice = optics::resolve(opt->model, simulator.optics(), dot_mm, opt->tolerance_dots);
        predict::ComparisonSettings settings;
        if (opt->chart_accuracy) {
            settings.accuracy_rays = parse_ray_counts(opt->accuracy_rays);
            settings.accuracy_models = parse_models(opt->models, simulator.optics(), dot_mm, opt->tolerance_dots);
            settings.reference_rays = opt->reference_rays;
        }
        // The field as the encoder saw it: same options, same lenslet samples, DESIGN's lenslets.
        const patterns::PatternGeometry& printed = pattern.geometry();
        const predict::EncodedField reference(
            design, opt->pattern,
            patterns::pattern_geometry(design, Dpi{printed.dpi_x}, Dpi{printed.dpi_y}, printed.margin_mm),
            pattern.tone().white, opt->field);
        const std::unique_ptr<optics::Transparency> through =
            choice.diffraction ? optics::diffracted(pattern, simulator.optics()) : nullptr;
        const predict::DisplayComparison comparison(
            simulator, through ? *through : static_cast<const optics::Transparency&>(pattern), reference.encoder(),
            pattern.tone());
        settings.sweep = opt->sweep;
        settings.lights = white_light_directions(opt->lights, opt->frame, reference.encoder().options().mapping);
        // A core's mean needs many rays (8 per side alias against the pixels: +-10 dB);
        // whole cells are within a dB at 8 (Design I, tests/test_compare.cpp).
        settings.options.rays_per_side = opt->rays > 0                       ? opt->rays
                                         : comparison.core().fraction < 1.0 ? 32
                                                                            : static_cast<int>(optics::kRaysPerSideOption.fallback);
        settings.options.pixels_per_pitch = opt->pixels_per_lenslet;
        settings.options.model = choice.model;

        predict::ComparisonRun run = predict::run_comparison(simulator, pattern, comparison, settings);
        run.summary.design = design.name;
        run.summary.pattern = opt->pattern;
        run.summary.field = opt->field;
        run.summary.model_choice = std::string(name_of(optics::kModelChoiceNames, opt->model));
        run.summary.paraxial_error_dots = choice.paraxial_error_dots;
        predict::write_comparison_report(opt->out, run, settings, {opt->view_pixels, opt->error_gain});
        if (opt->json) {
            std::printf("%s", predict::summary_text(run.summary).c_str());
            return;
        }
        std::fputs(predict::comparison_text(opt->out, run, settings.reference_rays).c_str(), stdout);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("  time         %.2f s\n", seconds);
    });
}

}  // namespace rfd::cli
