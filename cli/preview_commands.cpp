// rfd simulate preview: the pictures the preview page blends (predict/preview.hpp,
// project/preview.hpp).

#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "optics/diffraction.hpp"
#include "optics/analysis.hpp"
#include "optics/design.hpp"
#include "optics/display.hpp"
#include "predict/compare.hpp"
#include "predict/preview.hpp"
#include "print/printed.hpp"
#include "project/preview.hpp"

namespace rfd::cli {

void add_simulate_preview_command(CLI::App& simulate) {
    auto* cmd = simulate.add_subcommand(
        "preview", "The pictures of the preview page: the predicted display and the field relit in software over "
                   "a cone of light directions, with what the page needs to blend them as rfd does (Designs I and II)");
    struct Options {
        std::string design, pattern, field, out, direct;
        PrintOptions print;
        optics::ModelChoice model = optics::ModelChoice::Auto;
        std::size_t count = 0;  // add_option sets the defaults
        std::optional<double> max_angle_deg;
        int rays = 0;
        double pixels_per_lenslet = 8.0;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->design, "Design TOML file (Design I or II)")->required();
    cmd->add_option("PATTERN", opt->pattern, "Pattern file from `rfd pattern encode`")->required();
    cmd->add_option("FIELD", opt->field, "The reflectance field the pattern was encoded from (folder or .lp)")->required();
    cmd->add_option("--out", opt->out, "Output folder: data.js, predicted.png, relit.png")->required();
    add_option(*cmd, predict::kPreviewLightsOption, opt->count);
    cmd->add_option("--max-angle", opt->max_angle_deg,
                    "Largest angle to the display's axis, degrees (default: the field of view's edge)")
        ->check(CLI::Range(0.1, 89.0));
    add_option(*cmd, optics::kRaysPerSideOption, opt->rays);
    cmd->add_option("--pixels-per-lenslet", opt->pixels_per_lenslet, "Diffuser pixels per lenslet pitch")
        ->check(CLI::Range(1.0, 64.0));
    cmd->add_option("--direct", opt->direct,
                    "The direct encoding PATTERN was optimised from (`rfd pattern optimize --from`): its pictures too, "
                    "for the page's switch between the two");
    add_model_option(*cmd, opt->model);
    add_print_options(*cmd, opt->print);
    cmd->callback([opt] {
        const optics::Design design = optics::load_design(opt->design);
        const optics::DisplaySimulator simulator(design);
        const print::PrintedTransparency pattern = printed_pattern(design, opt->pattern, opt->print);
        const predict::EncodedField reference(design, opt->pattern, pattern.geometry(), pattern.tone().white, opt->field);
        const optics::ResolvedModel choice =
            optics::resolve(opt->model, simulator.optics(), {pattern.geometry().dot_x, pattern.geometry().dot_y});
        const std::unique_ptr<optics::Transparency> through =
            choice.diffraction ? optics::diffracted(pattern, simulator.optics()) : nullptr;
        const predict::DisplayComparison comparison(
            simulator, through ? *through : static_cast<const optics::Transparency&>(pattern), reference.encoder(),
            pattern.tone());
        double max_angle_deg = opt->max_angle_deg.value_or(0.0);
        if (!opt->max_angle_deg) max_angle_deg = field_of_view_half_angle_deg(simulator.optics(), opt->design);
        optics::SimulationOptions options;
        options.rays_per_side = opt->rays;
        options.pixels_per_pitch = opt->pixels_per_lenslet;
        options.model = choice.model;
        // The direct encoding an optimised pattern started from, for the page's switch.
        std::optional<print::PrintedTransparency> direct;
        std::optional<predict::DisplayComparison> direct_comparison;
        if (!opt->direct.empty()) {
            direct.emplace(printed_pattern(design, opt->direct, opt->print));
            if (std::abs(direct->tone().white - pattern.tone().white) > 1e-6 * pattern.tone().white)
                throw InputError(SourceLocation{opt->direct}, "--direct: not the pattern '" + opt->pattern +
                                                                  "' was optimised from (another rfd:white)");
            direct_comparison.emplace(simulator, *direct, reference.encoder(), direct->tone());
        }
        const predict::PreviewSet set =
            predict::preview_set(simulator, comparison, reference.encoder().options().mapping, opt->count,
                                 degrees_to_radians(max_angle_deg), options,
                                 direct_comparison ? &*direct_comparison : nullptr);
        project::write_preview_data(set, design.name, opt->out);
        std::printf("wrote %s/data.js: %zu light directions up to %.1f deg from the display's axis (display frame), "
                    "pictures of %d x %d lenslets, %s model, %d rays per side; scale %.6g (exposure %.4f stops)\n",
                    opt->out.c_str(), set.directions.size(), set.max_angle_deg, set.predicted.front().width(),
                    set.predicted.front().height(), std::string(optics::to_string(options.model)).c_str(), opt->rays,
                    set.scale, std::log2(set.scale));
    });
}

}  // namespace rfd::cli
