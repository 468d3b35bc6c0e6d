// rfd simulate: what a Design I or II display will show under given lights, predicted from
// its design and its pattern as printed, before anything is printed or built.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "cli/simulate_options.hpp"
#include "core/error.hpp"
#include "core/image_io.hpp"
#include "core/text.hpp"
#include "core/units.hpp"
#include "optics/diffraction.hpp"
#include "optics/display.hpp"
#include "optics/analysis.hpp"
#include "predict/display_lights.hpp"
#include "predict/prediction_report.hpp"
#include "predict/rti_export.hpp"
#include "relight/field.hpp"
#include "patterns/encode.hpp"
#include "print/printed.hpp"
#include "print/sheet.hpp"

namespace rfd::cli {
namespace {

CLI::App* add_simulate(CLI::App& app) {
    auto* cmd = app.add_subcommand(
        "simulate", "Predict what a display shows under given lights, from its design and its pattern as printed "
                    "(tone mapping, black level, density), before printing: Designs I/II on the diffuser, "
                    "III/IV from viewpoints; or a subcommand");
    cmd->require_subcommand(0, 1);
    auto opt = std::make_shared<SimulateOptions>();
    const auto observer_variant = add_observer_variant_options(*cmd);
    // Not ->required(): `rfd simulate SUBCOMMAND ...` has none of them (checked in the callback).
    cmd->add_option("DESIGN", opt->design, "Design TOML file");
    cmd->add_option("PATTERN", opt->pattern, "Pattern file from `rfd pattern encode`");
    cmd->add_option("--light", opt->lights,
                    std::string("A distant light behind the display, in the frame --frame names (in the display's, "
                                "0,0 is straight behind it) ") +
                        kLightSyntax + "; repeat for several");
    add_frame_option(*cmd, opt->frame);
    cmd->add_option("--envmap", opt->envmap,
                    "Light from an environment map: latitude-longitude radiance (.exr/.hdr) in the field's frame, "
                    "row 0 at the zenith, column W/2 facing +x; with or without --light");
    cmd->add_option("--out", opt->out, "Predicted diffuser image: .exr (linear) or .png (sRGB)");
    cmd->add_option("--lenslets", opt->lenslets,
                    "Also the picture at the display's resolution: the mean over each lenslet (.exr or .png)");
    cmd->add_option("--exposure", opt->exposure,
                    "Pictures (--out, --lenslets) multiplied by 2^STOPS, as a camera's exposure compensation: "
                    "-1 halves, so two lights that add up stay below white")
        ->check(CLI::Range(-20.0, 20.0));
    add_model_option(*cmd, opt->model);
    add_option(*cmd, optics::kModelToleranceOption, opt->tolerance_dots);
    add_print_options(*cmd, opt->print);
    add_option(*cmd, optics::kRaysPerSideOption, opt->rays);
    cmd->add_option("--pixels-per-lenslet", opt->pixels_per_lenslet, "Output pixels per lenslet pitch")
        ->check(CLI::Range(1.0, 64.0));
    cmd->add_option("--area-samples", opt->area_samples,
                    "At most this many directions per side of the grid over an area light's disc ("
                    "fewer when the disc spans fewer print dots)")
        ->check(CLI::Range(1, 64));
    cmd->add_option("--max-rays", opt->max_rays,
                    "Rays per lenslet over all directions together: a full grid per direction "
                    "while it fits, else an equal share each; also caps an environment map's directions")
        ->check(CLI::Range(1, 1 << 20));
    cmd->add_option("--front", opt->front,
                    "Contrast with light on the front too: front illuminance / back irradiance ratios "
                    "(0 is a dark room)")
        ->delimiter(',')
        ->check(non_negative_number());
    cmd->add_option("--diffuser-transmittance", opt->diffuser.transmittance,
                    "Fraction of the light from behind the diffuser passes to the observer (thesis "
                    "figure 8.7)")
        ->check(CLI::Range(0.0, 1.0));
    cmd->add_option("--diffuser-reflectance", opt->diffuser.reflectance,
                    "Fraction of the front light the diffuser scatters back to the observer (nominal)")
        ->check(CLI::Range(0.0, 1.0));
    cmd->add_flag("--json", opt->json, "Machine-readable summary");
    cmd->callback([cmd, opt, observer_variant] {
        if (!cmd->get_subcommands().empty()) return;  // a subcommand ran instead
        if (opt->design.empty()) throw CLI::RequiredError("DESIGN");
        if (opt->pattern.empty()) throw CLI::RequiredError("PATTERN");
        if (opt->lights.empty() && opt->envmap.empty()) throw CLI::RequiredError("--light or --envmap");
        if (opt->out.empty()) throw CLI::RequiredError("--out");
        const auto start = std::chrono::steady_clock::now();
        const optics::Design design = optics::load_design(opt->design);
        if (optics::is_observer_variant(design.kind))
            return simulate_observer_variant(*cmd, *opt, *observer_variant);
        const optics::DisplaySimulator simulator(design);
        const print::PrintedTransparency pattern = printed_pattern(design, opt->pattern, opt->print);

        const patterns::AngularMapping mapping = read_pattern_mapping(opt->pattern);
        std::vector<optics::DisplayLight> lights = to_display_lights(opt->lights, mapping, opt->frame);
        // Each named light where the display meets it, and a warning where it shows badly.
        std::vector<predict::LightCheck> checks;
        for (const optics::DisplayLight& light : lights) checks.push_back(predict::check_light(simulator.optics(), light, mapping));
        for (std::size_t k = 0; k < checks.size(); ++k)
            if (const std::string warning = checks[k].warning(); !warning.empty())
                std::fprintf(stderr, "rfd: warning: --light %s: %s\n", opt->lights[k].c_str(), warning.c_str());
        predict::EnvironmentSampling sampling;
        if (!opt->envmap.empty()) {
            const std::vector<optics::DisplayLight> sky = predict::environment_lights(
                read_image(opt->envmap), opt->envmap, mapping,
                predict::display_resolution_rad(simulator.optics(), mapping), opt->max_rays, &sampling);
            lights.insert(lights.end(), sky.begin(), sky.end());
        }
        if (lights.empty())
            throw InputError(SourceLocation{opt->envmap, 0, 0, ""},
                             "no light reaches the display from behind: the map is black there");
        optics::SimulationOptions options;
        options.rays_per_side = opt->rays;
        options.pixels_per_pitch = opt->pixels_per_lenslet;
        options.area_samples_per_side = opt->area_samples;
        options.max_rays_per_lenslet = opt->max_rays;
        const optics::ResolvedModel choice =
            optics::resolve(opt->model, simulator.optics(), {pattern.geometry().dot_x, pattern.geometry().dot_y},
                            opt->tolerance_dots);
        options.model = choice.model;
        const std::unique_ptr<optics::Transparency> through =
            choice.diffraction ? optics::diffracted(pattern, simulator.optics()) : nullptr;
        const optics::DiffuserImage result = simulator.simulate(through ? *through : static_cast<const optics::Transparency&>(pattern), lights, options);
        write_image(opt->out, result.image.exposed(opt->exposure));
        const Image picture = simulator.per_lenslet(result);
        if (!opt->lenslets.empty()) write_image(opt->lenslets, picture.exposed(opt->exposure));
        const predict::DiffuserPredictionReport report{
            opt->out, design.name, std::string(name_of(optics::kModelChoiceNames, opt->model)), choice,
            opt->tolerance_dots, opt->lights, opt->frame, checks, opt->envmap, sampling, &result,
            optics::picture_contrast(picture, opt->diffuser, opt->front), opt->diffuser, opt->exposure,
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()};
        if (opt->json)
            std::printf("%s\n", predict::to_json(report).dump(2).c_str());
        else
            std::fputs(predict::report_text(report).c_str(), stdout);
    });
    return cmd;
}

void add_rti_command(CLI::App& simulate) {
    auto* cmd = simulate.add_subcommand(
        "rti", "The predicted display as an RTI set (.lp and JPEGs, as CNR relight and RTIBuilder read them): one "
               "picture per light direction over the display's field of view (Designs I and II)");
    struct Options {
        std::string design, pattern, out;
        PrintOptions print;
        optics::ModelChoice model = optics::ModelChoice::Auto;
        std::size_t count = 64;
        std::optional<double> max_angle_deg;
        double exposure = 0.0;
        int rays = 0;  // add_option sets the default
        bool full = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->design, "Design TOML file (Design I or II)")->required();
    cmd->add_option("PATTERN", opt->pattern, "Pattern file from `rfd pattern encode`")->required();
    cmd->add_option("--out", opt->out, "Output folder: display.lp and display_NNNN.jpg")->required();
    cmd->add_option("--count", opt->count, "Light directions")->check(CLI::Range(1, 4096));
    cmd->add_option("--max-angle", opt->max_angle_deg,
                    "Largest angle to the display's axis, degrees (default: the field of view's edge, the smallest "
                    "wrap-over angle)")
        ->check(CLI::Range(0.1, 89.0));
    cmd->add_option("--exposure", opt->exposure, "Pictures multiplied by 2^STOPS before they are coded")
        ->check(CLI::Range(-20.0, 20.0));
    add_option(*cmd, optics::kRaysPerSideOption, opt->rays);
    cmd->add_flag("--full", opt->full, "The diffuser picture instead of one value per lenslet");
    add_model_option(*cmd, opt->model);
    add_print_options(*cmd, opt->print);
    cmd->callback([opt] {
        const optics::Design design = optics::load_design(opt->design);
        const optics::DisplaySimulator simulator(design);
        const print::PrintedTransparency pattern = printed_pattern(design, opt->pattern, opt->print);
        double max_angle_deg = opt->max_angle_deg.value_or(0.0);
        if (!opt->max_angle_deg) max_angle_deg = field_of_view_half_angle_deg(simulator.optics(), opt->design);
        optics::SimulationOptions options;
        options.rays_per_side = opt->rays;
        const optics::ResolvedModel choice =
            optics::resolve(opt->model, simulator.optics(), {pattern.geometry().dot_x, pattern.geometry().dot_y});
        options.model = choice.model;
        const std::unique_ptr<optics::Transparency> through =
            choice.diffraction ? optics::diffracted(pattern, simulator.optics()) : nullptr;
        const std::vector<Eigen::Vector3d> directions =
            predict::cone_directions(opt->count, degrees_to_radians(max_angle_deg), 1);
        relight::ReflectanceField shown =
            predict::predicted_field(simulator, through ? *through : static_cast<const optics::Transparency&>(pattern), directions, options, !opt->full);
        for (Image& image : shown.images) image = image.exposed(opt->exposure);
        relight::write_field(opt->out, shown, "display", ".jpg");
        std::printf("wrote %s/display.lp: %zu pictures of %d x %d, lights up to %.1f deg from the display's axis "
                    "(display frame), %s model%s\n",
                    opt->out.c_str(), shown.size(), shown.width(), shown.height(), max_angle_deg,
                    std::string(optics::to_string(options.model)).c_str(),
                    choice.diffraction ? " and the lenslets' diffraction" : "");
    });
}

}  // namespace

void add_simulate_commands(CLI::App& app) {
    CLI::App* simulate = add_simulate(app);
    add_rti_command(*simulate);
    add_simulate_tolerance_command(*simulate);
    add_simulate_compare_command(*simulate);
    add_simulate_verdict_command(*simulate);
    add_simulate_preview_command(*simulate);
}

}  // namespace rfd::cli
