// rfd simulate: what a Design I or II display will show under given lights, predicted from
// its design and its pattern as printed, before anything is printed or built.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/image_io.hpp"
#include "core/units.hpp"
#include "optics/display.hpp"
#include "patterns/encode.hpp"
#include "print/printed.hpp"
#include "print/sheet.hpp"

namespace rfd::cli {
namespace {

// A signed number from the pattern's rfd: attributes (the mapping it was encoded with).
double signed_attribute(const patterns::PatternFileInfo& info, const std::string& key, const std::string& file,
                        double fallback) {
    const auto it = info.attributes.find(key);
    if (it == info.attributes.end()) return fallback;
    std::size_t used = 0;
    double value = std::nan("");
    try {
        value = std::stod(it->second, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used != it->second.size() || !std::isfinite(value))
        throw InputError(SourceLocation{file, 0, 0, "rfd:" + key}, "expected a number, got '" + it->second + "'");
    return value;
}

// The field-frame lights of --light as the display meets them: through the angular
// mapping the pattern was encoded with, so a light at (theta, phi) shows what the field
// shows under a light from there.
std::vector<optics::DisplayLight> display_lights(const std::vector<std::string>& texts,
                                                 const patterns::AngularMapping& mapping) {
    std::vector<optics::DisplayLight> lights;
    for (const std::string& text : texts) {
        const relight::Light light = parse_light(text);
        optics::DisplayLight d;
        Eigen::Vector3d colour;
        if (const auto* point = std::get_if<relight::DirectionalLight>(&light)) {
            d.direction = mapping.display_direction(point->direction);
            colour = point->irradiance;
        } else {
            const auto& disc = std::get<relight::DiskLight>(light);
            d.direction = mapping.display_direction(disc.direction);
            d.angular_radius_rad = disc.radius / mapping.angle_scale;
            colour = disc.irradiance;
        }
        d.colour = {colour.x(), colour.y(), colour.z()};
        lights.push_back(d);
    }
    return lights;
}

CLI::App* add_simulate(CLI::App& app, const GlobalOptions& global) {
    auto* cmd = app.add_subcommand(
        "simulate", "Predict what a Design I or II display shows under given lights, from its design and its "
                    "pattern as printed (tone mapping, black level, density), before printing; or a subcommand");
    cmd->require_subcommand(0, 1);
    struct Options {
        std::string design, pattern, printer, out, lenslets, model = "auto";
        std::vector<std::string> lights;
        double tolerance_dots = 0.25, brightness = 1.0, pixels_per_lenslet = 8.0;
        int sheets = 0, rays = 8, area_samples = 5;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    // Not ->required(): `rfd simulate SUBCOMMAND ...` has none of them (checked in the callback).
    cmd->add_option("DESIGN", opt->design, "Design TOML file (Design I or II)");
    cmd->add_option("PATTERN", opt->pattern, "Pattern file from `rfd pattern encode`");
    cmd->add_option("--light", opt->lights,
                    std::string("A distant light behind the display, in the field's frame ") + kLightSyntax +
                        "; repeat for several");
    cmd->add_option("--out", opt->out, "Predicted diffuser image: .exr (linear) or .png (sRGB)");
    cmd->add_option("--lenslets", opt->lenslets,
                    "Also the picture at the display's resolution: the mean over each lenslet (.exr or .png)");
    cmd->add_option("--model", opt->model, "paraxial, exact, or auto (paraxial where it is within --tolerance)")
        ->check(CLI::IsMember({"paraxial", "exact", "auto"}));
    cmd->add_option("--tolerance", opt->tolerance_dots,
                    "auto: largest paraxial error on the pattern plane, in print dots (default 0.25)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--printer", opt->printer, "Printer profile (tone mapping); default the Epson's at the design's dpi");
    cmd->add_option("--brightness", opt->brightness, "Tone mapping: transmittance = brightness * value / white")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--sheets", opt->sheets, "Sheets back to back (1 or 2); default the profile's");
    cmd->add_option("--rays", opt->rays, "Rays per side of each lenslet's grid (default 8)")->check(CLI::Range(1, 256));
    cmd->add_option("--pixels-per-lenslet", opt->pixels_per_lenslet, "Output pixels per lenslet pitch (default 8)")
        ->check(CLI::Range(1.0, 64.0));
    cmd->add_option("--area-samples", opt->area_samples,
                    "Directions per side of the grid over an area light's disc (default 5)")
        ->check(CLI::Range(1, 64));
    cmd->add_flag("--json", opt->json, "Machine-readable summary");
    cmd->callback([cmd, opt, &global] {
        (void)global;
        if (!cmd->get_subcommands().empty()) return;  // a subcommand ran instead
        if (opt->design.empty()) throw CLI::RequiredError("DESIGN");
        if (opt->pattern.empty()) throw CLI::RequiredError("PATTERN");
        if (opt->lights.empty()) throw CLI::RequiredError("--light");
        if (opt->out.empty()) throw CLI::RequiredError("--out");
        const auto start = std::chrono::steady_clock::now();
        const optics::Design design = optics::load_design(opt->design);
        const optics::DisplaySimulator simulator(design);
        const print::PrinterProfile printer = printer_for(design, opt->printer);
        const print::PrintedTransparency pattern(design, printer, opt->pattern, opt->brightness, opt->sheets);

        const patterns::PatternFileInfo info = patterns::read_pattern_info(opt->pattern);
        patterns::AngularMapping mapping;
        mapping.tilt_deg = signed_attribute(info, "tilt_deg", opt->pattern, 0.0);
        mapping.turn_deg = signed_attribute(info, "turn_deg", opt->pattern, 0.0);
        mapping.angle_scale = signed_attribute(info, "angle_scale", opt->pattern, 1.0);
        if (!(mapping.angle_scale > 0.0))
            throw InputError(SourceLocation{opt->pattern, 0, 0, "rfd:angle_scale"}, "expected a positive number");
        const std::vector<optics::DisplayLight> lights = display_lights(opt->lights, mapping);

        optics::SimulationOptions options;
        options.rays_per_side = opt->rays;
        options.pixels_per_pitch = opt->pixels_per_lenslet;
        options.area_samples_per_side = opt->area_samples;
        const patterns::ModelChoice choice = patterns::choose_model(design, pattern.geometry(), opt->tolerance_dots);
        options.model = opt->model == "paraxial" ? optics::Model::Paraxial
                        : opt->model == "exact"  ? optics::Model::Exact
                                                 : choice.model;
        const optics::DiffuserImage result = simulator.simulate(pattern, lights, options);
        write_image(opt->out, result.image);
        if (!opt->lenslets.empty()) write_image(opt->lenslets, simulator.per_lenslet(result));
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

        const std::string model(optics::to_string(options.model));
        const nlohmann::json summary = {
            {"out", opt->out},
            {"model", model},
            {"model_choice", opt->model},
            {"paraxial_error_dots", choice.paraxial_error_dots},
            {"lights", opt->lights.size()},
            {"directions", result.directions},
            {"rays", result.rays},
            {"rays_lost", result.lost},
            {"rays_crossed", result.crossed},
            {"optical_efficiency", result.optical_efficiency},
            {"pattern_efficiency", result.pattern_efficiency},
            {"pixels", {result.image.width(), result.image.height()}},
            {"pixel_mm", result.pixel_mm},
            {"seconds", seconds}};
        if (opt->json) {
            std::printf("%s\n", summary.dump(2).c_str());
            return;
        }
        std::printf("%s: %d x %d pixels of %.4f mm, what '%s' shows\n", opt->out.c_str(), result.image.width(),
                    result.image.height(), result.pixel_mm, design.name.c_str());
        std::printf("  model        %s (%s; paraxial error up to %.2f dots, tolerance %.2f)\n", model.c_str(),
                    opt->model == "auto" ? "chosen automatically" : "as asked", choice.paraxial_error_dots,
                    opt->tolerance_dots);
        std::printf("  light        %zu light(s), %zu direction(s) sampled, %zu rays\n", opt->lights.size(),
                    result.directions, result.rays);
        std::printf("  efficiency   %.1f %% of the light entering the lenslets reaches the diffuser; "
                    "%.1f / %.1f / %.1f %% through the pattern (R/G/B)\n",
                    100 * result.optical_efficiency, 100 * result.pattern_efficiency[0],
                    100 * result.pattern_efficiency[1], 100 * result.pattern_efficiency[2]);
        std::printf("  crosstalk    %.2f %% of the rays reach the diffuser through a neighbouring lenslet\n",
                    result.rays ? 100.0 * static_cast<double>(result.crossed) / static_cast<double>(result.rays) : 0.0);
        std::printf("  time         %.2f s\n", seconds);
    });
    return cmd;
}

}  // namespace

void add_simulate_commands(CLI::App& app, const GlobalOptions& global) {
    CLI::App* simulate = add_simulate(app, global);
    add_simulate_compare_command(*simulate, global);
}

}  // namespace rfd::cli
