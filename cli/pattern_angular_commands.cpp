// rfd pattern encode-angular: the pattern of a Design III/IV display from a view set, a
// single field, or a procedural field (figure 8.13's letters, figure 8.15's diamonds).

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/text.hpp"
#include "core/units.hpp"
#include "patterns/angular.hpp"
#include "relight/view_set.hpp"

namespace rfd::cli {

// A single field folder (or .lp) is a view set of one head-on view.
relight::ViewSet read_angular_source(const std::filesystem::path& source, const relight::ImageWindow& window) {
    const bool field_folder = std::filesystem::is_directory(source) && !std::filesystem::exists(source / "views.txt");
    if (!field_folder && source.extension() != ".lp") return relight::read_view_set(source, window);
    relight::ViewSet set;
    set.file = relight::light_file_of(source);
    set.views.push_back({source.string(), Eigen::Vector3d::UnitZ(), Eigen::Matrix3d::Identity(), 0});
    set.fields.push_back(relight::read_field(source, window));
    return set;
}

void add_angular_source_options(CLI::App& command, AngularSource& source) {
    command.add_option("--procedural", source.procedural,
                       "Instead of SOURCE: letters (Design III, figure 8.13) or diamonds (Design IV, figure 8.15)")
        ->check(CLI::IsMember({"letters", "diamonds"}));
    command.add_option("--text", source.text, "Characters of the letters field, one per incident bin");
    command.add_option("--coverage", source.coverage,
                       "Fraction of each view image (about its centre, after --region and --scale) the macro grid covers")
        ->check(CLI::Range(1e-3, 1.0));
    add_window_options(command, source.window);
}

std::unique_ptr<patterns::AngularField> angular_field(const AngularSource& source, const optics::MesoPixelOptics& meso,
                                                      optics::Model model) {
    if (source.procedural == "letters")
        return std::make_unique<patterns::LetterField>(patterns::letter_field_for(meso, model, source.text));
    if (source.procedural == "diamonds")
        return std::make_unique<patterns::DiamondField>(patterns::diamond_field_for(meso, model));
    // --region was the coverage fraction once: say where it went.
    if (!source.window.region.empty() && source.window.region.find(',') == std::string::npos)
        throw InputError("--region takes X,Y,W,H in pixels, as every command that reads images does; the "
                         "fraction of each view the macro grid covers is --coverage");
    return std::make_unique<patterns::ViewSetField>(read_angular_source(source.path, source.window.window()),
                                                    source.coverage);
}

void add_pattern_angular_command(CLI::App& group) {
    auto* cmd = group.add_subcommand(
        "encode-angular", "Encode a Design III/IV pattern: R(incident bin; macro-pixel; output direction)");
    struct Options {
        std::string design, out;
        AngularSource source;
        optics::ModelChoice model = optics::ModelChoice::Auto;
        double dpi = 0.0;
        int bin_samples = 3, table = 129;
        bool json = false, single = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->design, "Design III or IV file (designs/design3.toml, design4.toml)")->required();
    cmd->add_option("SOURCE", opt->source.path, "View set (folder with views.txt, or the file) or one field folder");
    add_angular_source_options(*cmd, opt->source);
    cmd->add_option("--out", opt->out, "Pattern file (.exr linear; .tif/.png sRGB)")->required();
    add_model_option(*cmd, opt->model);
    cmd->add_option("--dpi", opt->dpi, "Print resolution on both axes (default: the design's printer)")->check(positive_number());
    cmd->add_option("--bin-samples", opt->bin_samples, "Incident directions per side of each bin")->check(CLI::Range(1, 16));
    cmd->add_option("--table", opt->table, "Optics table nodes per side of a meso cell")->check(CLI::Range(3, 4097));
    cmd->add_flag("--single-float", opt->single, "EXR: 32-bit floats instead of half floats");
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        const auto start = std::chrono::steady_clock::now();
        if (opt->source.path.empty() == opt->source.procedural.empty())
            throw InputError("give either SOURCE (a view set or a field) or --procedural letters|diamonds");
        const optics::DesignOptics optics(optics::load_design(opt->design));
        const optics::MesoPixelOptics meso(optics);
        patterns::AngularOptions options;
        options.model = optics::resolve(opt->model, optics, optics.dot_mm()).model;
        options.bin_samples = opt->bin_samples;
        options.table_size = opt->table;
        options.dpi_x = options.dpi_y = opt->dpi;
        const std::unique_ptr<patterns::AngularField> field = angular_field(opt->source, meso, options.model);
        const patterns::AngularPattern pattern(optics, *field, options);
        const double white = patterns::estimate_white(pattern, 99.5);
        patterns::PatternAttributes attributes = pattern.attributes();
        attributes["white"] = format_number(white, 9);
        attributes["source"] = opt->source.procedural.empty() ? opt->source.path : "procedural " + opt->source.procedural;
        patterns::WriteOptions write;
        write.half_float = !opt->single;
        patterns::write_pattern(opt->out, pattern, attributes, write);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        const auto& g = pattern.geometry();
        const patterns::DotCounts counts = pattern.counts();
        if (opt->json) {
            const nlohmann::json summary = {
                {"out", opt->out},
                {"design", opt->design},
                {"model", std::string(optics::to_string(options.model))},
                {"source", attributes["source"]},
                {"size", {g.width, g.height}},
                {"dpi", {g.dpi_x, g.dpi_y}},
                {"channels", pattern.channels()},
                {"bins", pattern.bins().size()},
                {"macro_grid", {pattern.macro_x(), pattern.macro_y()}},
                {"lit_fraction", counts.lit_fraction()},
                {"output_focal_length_mm", -1.0 / meso.output_gain()},
                {"output_spread_deg", radians_to_degrees(std::atan(meso.output_spread().x()))},
                {"white", white},
                {"seconds", seconds}};
            std::printf("%s\n", summary.dump(2).c_str());
        } else {
            std::printf("wrote %s: %d x %d dots at %g x %g dpi, %d channel(s)\n", opt->out.c_str(), g.width, g.height,
                        g.dpi_x, g.dpi_y, pattern.channels());
            std::printf("  incident bins      %zu (meso cells), macro grid %d x %d, %s optics\n", pattern.bins().size(),
                        pattern.macro_x(), pattern.macro_y(), std::string(optics::to_string(options.model)).c_str());
            std::printf("  lit dots           %.1f %% of each meso cell (the rest lie outside the main lens's image or cross)\n",
                        100.0 * counts.lit_fraction());
            std::printf("  output             f = %.3f mm, dot blur +-%.2f deg\n", -1.0 / meso.output_gain(),
                        radians_to_degrees(std::atan(meso.output_spread().x())));
            std::printf("  white (99.5 %%)     %.6g\n", white);
            std::printf("  time               %.2f s\n", seconds);
        }
    });
}

}  // namespace rfd::cli
