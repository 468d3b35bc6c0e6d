// rfd simulate verdict: go / check / no-go for a display, from what simulate compare and
// simulate tolerance wrote and the design's own analysis (predict/verdict.hpp).

#include <cstdio>
#include <fstream>
#include <memory>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/text.hpp"
#include "optics/analysis.hpp"
#include "optics/design.hpp"
#include "optics/design_optics.hpp"
#include "predict/verdict.hpp"

namespace rfd::cli {
namespace {

// A summary.json another command wrote, with errors that name it.
nlohmann::json read_summary(const std::filesystem::path& folder, const std::string& option) {
    const std::filesystem::path file = folder / "summary.json";
    std::ifstream in(file);
    if (!in) throw IoError(SourceLocation{file.string(), 0, 0, option}, "cannot open (expected the folder that rfd simulate " + option.substr(2) + " --out wrote)");
    try {
        return nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception& error) {
        throw InputError(SourceLocation{file.string()}, std::string("not a summary rfd wrote: ") + error.what());
    }
}

std::optional<double> optional_number(const nlohmann::json& value) {
    return value.is_number() ? std::optional<double>(value.get<double>()) : std::nullopt;
}

}  // namespace

void add_simulate_verdict_command(CLI::App& simulate) {
    auto* cmd = simulate.add_subcommand(
        "verdict", "Go / check / no-go for printing a display: the predicted PSNR over the field of view, the "
                   "crosstalk-free cone, the assembly tolerances and the design's warnings");
    struct Options {
        std::string design, compare, tolerance, out;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->design, "Design TOML file (Design I or II)")->required();
    cmd->add_option("--compare", opt->compare, "Folder that rfd simulate compare wrote")->required();
    cmd->add_option("--tolerance", opt->tolerance, "Folder that rfd simulate tolerance wrote (optional)");
    cmd->add_option("--out", opt->out, "Also write the verdict as JSON here");
    cmd->add_flag("--json", opt->json, "Machine-readable verdict on stdout");
    cmd->callback([opt] {
        const optics::Design design = optics::load_design(opt->design);
        const optics::DesignSummary analysis = optics::summarise(optics::DesignOptics(design));
        predict::VerdictInputs inputs;
        std::set<std::string> at_least;  // tolerances the sweep only bounded from below
        inputs.design = design.name;
        inputs.field_of_view_deg = analysis.field_of_view_deg;
        for (const auto& [direction, onset] : analysis.crosstalk_exact_deg)
            if (onset)
                inputs.crosstalk_free_cone_deg = std::min(inputs.crosstalk_free_cone_deg.value_or(1e300), 2.0 * *onset);
        inputs.warnings = analysis.warnings;
        const nlohmann::json compare = read_summary(opt->compare, "--compare");
        try {
            for (const auto& d : compare.at("directions"))
                inputs.directions.push_back({d.at("display_angle_deg").get<double>(), d.at("inside_fov").get<bool>(),
                                             d.at("crosstalk_free").get<bool>(), d.at("mse").get<double>(),
                                             d.at("peak").get<double>()});
            if (!opt->tolerance.empty()) {
                predict::AssemblyTolerances t;
                const nlohmann::json tolerance = read_summary(opt->tolerance, "--tolerance");
                for (const auto& curve : tolerance.at("curves")) {
                    const std::string kind = curve.at("kind").get<std::string>();
                    // A sweep that never fell below the threshold bounds the tolerance from
                    // below by its largest error.
                    std::optional<double> value = optional_number(curve.at("tolerance"));
                    if (!value) {
                        value = optional_number(curve.at("max"));
                        if (value) at_least.insert(kind);
                    }
                    if (kind == "shift") t.shift_mm = value;
                    if (kind == "rotation") t.rotation_deg = value;
                    if (kind == "pitch_error") t.pitch_ppm = value;
                    if (kind == "spacer") t.spacer_mm = value;
                }
                inputs.tolerances = t;
            }
        } catch (const nlohmann::json::exception& error) {
            throw InputError(std::string("a summary.json lacks what rfd simulate writes: ") + error.what());
        }
        const predict::Verdict v = predict::judge(inputs);
        const auto tolerance_json = [&](const std::optional<double>& value) { return json_or_null(value); };
        nlohmann::json tolerances = nullptr;
        if (inputs.tolerances)
            tolerances = {{"shift_mm", tolerance_json(inputs.tolerances->shift_mm)},
                          {"rotation_deg", tolerance_json(inputs.tolerances->rotation_deg)},
                          {"pitch_error_ppm", tolerance_json(inputs.tolerances->pitch_ppm)},
                          {"spacer_mm", tolerance_json(inputs.tolerances->spacer_mm)},
                          {"at_least", at_least}};
        const nlohmann::json json = {{"design", design.name},
                                     {"call", std::string(predict::to_string(v.call))},
                                     {"reason", v.reason},
                                     {"line", v.line()},
                                     {"psnr_mean_in_fov_db", json_or_null(v.psnr_mean_in_fov_db)},
                                     {"psnr_min_in_fov_db", json_or_null(v.psnr_min_in_fov_db)},
                                     {"psnr_mean_crosstalk_free_db", json_or_null(v.psnr_mean_crosstalk_free_db)},
                                     {"directions_in_fov", v.directions_in_fov},
                                     {"directions_crosstalk_free", v.directions_crosstalk_free},
                                     {"field_of_view_deg", json_or_null(inputs.field_of_view_deg)},
                                     {"crosstalk_free_cone_deg", json_or_null(inputs.crosstalk_free_cone_deg)},
                                     {"tolerances", tolerances},
                                     {"warnings", inputs.warnings}};
        if (!opt->out.empty()) write_text_file(opt->out, json.dump(2) + "\n");
        if (opt->json) {
            std::printf("%s\n", json.dump(2).c_str());
            return;
        }
        const auto number = [](const std::optional<double>& value, const char* unit) {
            return value ? format_fixed(*value, 2) + unit : std::string("-");
        };
        const auto bound = [&](const std::optional<double>& value, const char* unit, const std::string& kind) {
            return number(value, unit) + (at_least.count(kind) ? " or more" : "");
        };
        std::printf("%s\n", v.line().c_str());
        std::printf("  design                  %s\n", design.name.c_str());
        std::printf("  PSNR over the FOV       mean %s, min %s (%d direction(s); against the field's brightest)\n",
                    number(v.psnr_mean_in_fov_db, " dB").c_str(), number(v.psnr_min_in_fov_db, " dB").c_str(),
                    v.directions_in_fov);
        std::printf("  crosstalk-free cone     %s full cone, PSNR mean %s (%d direction(s))\n",
                    number(inputs.crosstalk_free_cone_deg, " deg").c_str(),
                    number(v.psnr_mean_crosstalk_free_db, " dB").c_str(), v.directions_crosstalk_free);
        std::printf("  field of view           %s full cone\n", number(inputs.field_of_view_deg, " deg").c_str());
        if (inputs.tolerances)
            std::printf("  tolerances              shift %s, rotation %s, pitch %s, spacer %s\n",
                        bound(inputs.tolerances->shift_mm, " mm", "shift").c_str(),
                        bound(inputs.tolerances->rotation_deg, " deg", "rotation").c_str(),
                        bound(inputs.tolerances->pitch_ppm, " ppm", "pitch_error").c_str(),
                        bound(inputs.tolerances->spacer_mm, " mm", "spacer").c_str());
        for (const std::string& warning : inputs.warnings) std::printf("  warning                 %s\n", warning.c_str());
    });
}

}  // namespace rfd::cli
