// rfd design advise: what a design makes of the user's own field before anything long runs
// (patterns/advice.hpp): its picture elements against the field's pixels, the lights inside
// its range at the tilt asked for and at the best one, and the bundled design that shows the
// field best.

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/files.hpp"
#include "optics/design.hpp"
#include "patterns/advice.hpp"
#include "patterns/encode.hpp"
#include "project/project.hpp"
#include "relight/field.hpp"

namespace rfd::cli {
namespace {

nlohmann::json tilt_json(const patterns::TiltChoice& t) {
    return {{"tilt_deg", t.tilt_deg},
            {"lights_inside", t.lights.inside},
            {"lights", t.lights.total},
            {"range_surrounded", t.lights.covered}};
}

nlohmann::json fit_json(const patterns::DesignFit& f) {
    return {{"name", f.name},           {"file", f.file},
            {"kind", f.kind},           {"picture_elements", {f.elements_x, f.elements_y}},
            {"encodes_pictures", f.encodes_pictures},
            {"at_given_tilt", tilt_json(f.at_given)},
            {"at_best_tilt", tilt_json(f.at_best)},
            {"shown_elements", f.shown_elements}};
}

// The bundled designs, in name order.
std::vector<std::string> bundled_designs() {
    std::vector<std::string> files;
    for (const auto& entry : std::filesystem::directory_iterator(project::bundled_design_folder()))
        if (entry.is_regular_file() && entry.path().extension() == ".toml") files.push_back(entry.path().string());
    std::sort(files.begin(), files.end());
    return files;
}

}  // namespace

void add_design_advise_command(CLI::App& design_cmd) {
    auto* cmd = design_cmd.add_subcommand(
        "advise", "What a design makes of a field before the long steps: picture elements against the field's pixels, "
                  "the lights inside the display's range, the best tilt, the bundled design that shows it best");
    struct Options {
        std::string design, field, out, tilt_text = "0";
        double turn = 0, angle_scale = 0;
        WindowOptions window;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->design, "Design file")->required();
    cmd->add_option("FIELD", opt->field, "Reflectance field folder or .lp file")->required();
    cmd->add_option("--tilt", opt->tilt_text, std::string(patterns::kTiltAutoHelp) + " (degrees)")->capture_default_str();
    add_option(*cmd, patterns::kTurnOption, opt->turn);
    add_option(*cmd, patterns::kAngleScaleOption, opt->angle_scale);
    add_window_options(*cmd, opt->window);
    cmd->add_option("--out", opt->out, "Also write the advice as JSON (for rfd make's page)");
    cmd->add_flag("--json", opt->json, "Machine-readable advice on stdout");
    cmd->callback([opt] {
        const optics::Design design = optics::load_design(opt->design);
        const relight::FieldReader field(opt->field, opt->window.window());
        const std::vector<Eigen::Vector3d> directions = field.directions();
        patterns::AngularMapping mapping{0.0, opt->turn, opt->angle_scale};
        const std::optional<double> tilt = patterns::parse_tilt(opt->tilt_text, "--tilt");
        if (tilt)
            mapping.tilt_deg = *tilt;
        else
            mapping.tilt_deg = patterns::best_tilt(optics::DesignOptics(design), directions, mapping).tilt_deg;
        const patterns::Advice advice = patterns::advise(design, opt->design, bundled_designs(), opt->field,
                                                         field.width(), field.height(), directions, mapping);
        const nlohmann::json out{{"design", opt->design},
                                 {"field", opt->field},
                                 {"field_pixels", {advice.field_width, advice.field_height}},
                                 {"lights", advice.lights},
                                 {"tilt", opt->tilt_text},
                                 {"chosen", fit_json(advice.chosen)},
                                 {"bundled", [&] {
                                      nlohmann::json list = nlohmann::json::array();
                                      for (const auto& f : advice.bundled) list.push_back(fit_json(f));
                                      return list;
                                  }()},
                                 {"best", advice.best >= 0 ? nlohmann::json(advice.bundled[static_cast<std::size_t>(advice.best)].file)
                                                           : nlohmann::json()},
                                 {"lines", advice.lines}};
        if (!opt->out.empty()) write_text_file(opt->out, out.dump(2) + "\n");
        if (opt->json) {
            std::printf("%s\n", out.dump(2).c_str());
        } else {
            for (const std::string& line : advice.lines) std::printf("%s\n", line.c_str());
        }
    });
}

}  // namespace rfd::cli
