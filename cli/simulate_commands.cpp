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
#include "optics/display.hpp"
#include "optics/analysis.hpp"
#include "predict/display_lights.hpp"
#include "predict/rti_export.hpp"
#include "relight/field.hpp"
#include "patterns/encode.hpp"
#include "print/printed.hpp"
#include "print/sheet.hpp"

namespace rfd::cli {
namespace {

nlohmann::json light_checks_json(const std::vector<predict::LightCheck>& checks) {
    nlohmann::json out = nlohmann::json::array();
    for (const predict::LightCheck& c : checks)
        out.push_back({{"display_deg", {c.display_theta_deg, c.display_phi_deg}},
                       {"field_deg", {c.field_theta_deg, c.field_phi_deg}},
                       {"angle_to_axis_deg", c.display_theta_deg},
                       {"wrap_over_deg", json_or_null(c.wrap_over_deg)},
                       {"crosstalk_onset_deg", json_or_null(c.crosstalk_deg)},
                       {"warning", c.warning()}});
    return out;
}

void print_light_check(const std::string& text, const predict::LightCheck& c) {
    std::printf("               %s: display %s, field %s; %s deg from the axis (field of view to %s, crosstalk from "
                "%s deg along its azimuth)\n",
                text.c_str(), (format_fixed(c.display_theta_deg, 1) + "," + format_fixed(c.display_phi_deg, 1)).c_str(),
                (format_fixed(c.field_theta_deg, 1) + "," + format_fixed(c.field_phi_deg, 1)).c_str(),
                format_fixed(c.display_theta_deg, 1).c_str(),
                c.wrap_over_deg ? format_fixed(*c.wrap_over_deg, 1).c_str() : "89+",
                c.crosstalk_deg ? format_fixed(*c.crosstalk_deg, 1).c_str() : "89+");
}

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
        if (design.kind == optics::DesignKind::III || design.kind == optics::DesignKind::IV)
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
        const optics::DiffuserImage result = simulator.simulate(pattern, lights, options);
        write_image(opt->out, result.image.exposed(opt->exposure));
        const Image picture = simulator.per_lenslet(result);
        if (!opt->lenslets.empty()) write_image(opt->lenslets, picture.exposed(opt->exposure));
        const optics::PictureContrast contrast = optics::picture_contrast(picture, opt->diffuser, opt->front);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

        const std::string model(optics::to_string(options.model));
        nlohmann::json summary = {
            {"out", opt->out},
            {"model", model},
            {"model_choice", std::string(name_of(optics::kModelChoiceNames, opt->model))},
            {"paraxial_error_dots", json_or_null(choice.paraxial_error_dots)},
            {"lights", opt->lights.size()},
            {"frame", std::string(name_of(predict::kLightFrameNames, opt->frame))},
            {"light_checks", light_checks_json(checks)},
            {"directions", result.directions},
            {"rays_per_direction", result.rays_per_direction},
            {"rays", result.rays},
            {"rays_lost", result.lost},
            {"rays_crossed", result.crossed},
            {"optical_efficiency", result.optical_efficiency},
            {"pattern_efficiency", result.pattern_efficiency},
            {"pixels", {result.image.width(), result.image.height()}},
            {"pixel_mm", result.pixel_mm},
            {"exposure_stops", opt->exposure},
            {"seconds", seconds}};
        nlohmann::json front = nlohmann::json::array();
        for (const optics::FrontLightContrast& c : contrast.with_front)  // JSON has no infinity: null
            front.push_back({{"front_ratio", c.front_ratio},
                             {"contrast", std::isfinite(c.contrast) ? nlohmann::json(c.contrast) : nlohmann::json()}});
        summary["contrast"] = {{"white", contrast.white},
                               {"black", contrast.black},
                               {"transmissivity", contrast.transmissivity},
                               {"diffuser_transmittance", opt->diffuser.transmittance},
                               {"diffuser_reflectance", opt->diffuser.reflectance},
                               {"with_front_light", front}};
        if (!opt->envmap.empty())
            summary["envmap"] = environment_json(opt->envmap, sampling);
        if (opt->json) {
            std::printf("%s\n", summary.dump(2).c_str());
            return;
        }
        std::printf("%s: %d x %d pixels of %.4f mm, what '%s' shows\n", opt->out.c_str(), result.image.width(),
                    result.image.height(), result.pixel_mm, design.name.c_str());
        std::printf("  model        %s (%s; paraxial error up to %.2f dots, tolerance %.2f)\n", model.c_str(),
                    opt->model == optics::ModelChoice::Auto ? "chosen automatically" : "as asked",
                    choice.paraxial_error_dots.value_or(0.0), opt->tolerance_dots);
        std::printf("  light        %zu light(s)%s, %zu direction(s) sampled, %zu ray(s) per direction and lenslet, "
                    "%zu rays\n",
                    opt->lights.size(), opt->envmap.empty() ? "" : " and an environment map", result.directions,
                    result.rays_per_direction, result.rays);
        for (std::size_t k = 0; k < checks.size(); ++k) print_light_check(opt->lights[k], checks[k]);
        if (!opt->envmap.empty()) print_environment_line(opt->envmap, sampling);
        std::printf("  efficiency   %.1f %% of the light entering the lenslets reaches the diffuser; "
                    "%.1f / %.1f / %.1f %% through the pattern (R/G/B)\n",
                    100 * result.optical_efficiency, 100 * result.pattern_efficiency[0],
                    100 * result.pattern_efficiency[1], 100 * result.pattern_efficiency[2]);
        std::printf("  crosstalk    %.2f %% of the rays reach the diffuser through a neighbouring lenslet\n",
                    result.rays ? 100.0 * static_cast<double>(result.crossed) / static_cast<double>(result.rays) : 0.0);
        std::printf("  contrast     white %.4f, black %.4f (99th / 1st percentile over the lenslets); %.1f %% as bright "
                    "as the back light through the diffuser\n",
                    contrast.white, contrast.black, 100 * contrast.transmissivity);
        for (const optics::FrontLightContrast& c : contrast.with_front) {
            if (std::isfinite(c.contrast))
                std::printf("               %.1f : 1 with front / back light %g%s\n", c.contrast, c.front_ratio,
                            c.front_ratio == 0.0 ? " (dark room)" : "");
            else
                std::printf("               unbounded with front / back light %g%s (the blacks are black)\n",
                            c.front_ratio, c.front_ratio == 0.0 ? " (dark room)" : "");
        }
        std::printf("  time         %.2f s\n", seconds);
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
        options.model = optics::resolve(opt->model, simulator.optics(),
                                        {pattern.geometry().dot_x, pattern.geometry().dot_y})
                            .model;
        const std::vector<Eigen::Vector3d> directions =
            predict::cone_directions(opt->count, degrees_to_radians(max_angle_deg), 1);
        relight::ReflectanceField shown = predict::predicted_field(simulator, pattern, directions, options, !opt->full);
        for (Image& image : shown.images) image = image.exposed(opt->exposure);
        relight::write_field(opt->out, shown, "display", ".jpg");
        std::printf("wrote %s/display.lp: %zu pictures of %d x %d, lights up to %.1f deg from the display's axis "
                    "(display frame), %s model\n",
                    opt->out.c_str(), shown.size(), shown.width(), shown.height(), max_angle_deg,
                    std::string(optics::to_string(options.model)).c_str());
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
