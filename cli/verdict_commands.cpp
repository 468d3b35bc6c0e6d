// rfd simulate verdict: go / check / no-go for a display, from what simulate compare and
// simulate tolerance wrote and the design's own analysis (predict/verdict.hpp).

#include <cstdio>
#include <fstream>
#include <memory>
#include <set>
#include <string>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/text.hpp"
#include "optics/analysis.hpp"
#include "optics/design.hpp"
#include "optics/design_optics.hpp"
#include "predict/summaries.hpp"
#include "predict/verdict.hpp"

namespace rfd::cli {

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
        const auto compare = predict::read_summary<predict::CompareSummary>(summary_file(opt->compare, "--compare"));
        for (const predict::CompareDirection& d : compare.directions)
            inputs.directions.push_back({d.display_angle_deg, d.inside_fov, d.crosstalk_free, d.mse, d.peak});
        if (!opt->tolerance.empty()) {
            predict::AssemblyTolerances t;
            const auto tolerance = predict::read_summary<predict::ToleranceSummary>(summary_file(opt->tolerance, "--tolerance"));
            for (const predict::ToleranceCurveRecord& curve : tolerance.curves) {
                // A sweep that never fell below the threshold bounds the tolerance from below
                // by its largest error.
                const double value = curve.tolerance.value_or(curve.max);
                if (!curve.tolerance) at_least.insert(curve.kind);
                if (curve.kind == "shift") t.shift_mm = value;
                if (curve.kind == "rotation") t.rotation_deg = value;
                if (curve.kind == "pitch_error") t.pitch_ppm = value;
                if (curve.kind == "spacer") t.spacer_mm = value;
            }
            inputs.tolerances = t;
        }
        const predict::Verdict v = predict::judge(inputs);
        const predict::VerdictReport report =
            predict::verdict_report(v, std::vector<std::string>(at_least.begin(), at_least.end()));
        if (!opt->out.empty()) predict::write_summary(opt->out, report);
        if (opt->json) {
            std::printf("%s", predict::summary_text(report).c_str());
            return;
        }
        const auto number = [](const std::optional<double>& value, const char* unit) {
            return value ? format_fixed(*value, 2) + unit : std::string("-");
        };
        std::printf("%s\n", v.line().c_str());
        std::printf("  on this field           %s\n", v.on_field.line().c_str());
        std::printf("  on the design           %s\n", v.on_design.line().c_str());
        std::printf("  design                  %s\n", design.name.c_str());
        std::printf("  PSNR over the FOV       mean %s, min %s (%d direction(s); against the field's brightest)\n",
                    number(v.psnr_mean_in_fov_db, " dB").c_str(), number(v.psnr_min_in_fov_db, " dB").c_str(),
                    v.directions_in_fov);
        std::printf("  crosstalk-free cone     %s full cone, PSNR mean %s (%d direction(s))\n",
                    number(inputs.crosstalk_free_cone_deg, " deg").c_str(),
                    number(v.psnr_mean_crosstalk_free_db, " dB").c_str(), v.directions_crosstalk_free);
        std::printf("  field of view           %s full cone\n", number(inputs.field_of_view_deg, " deg").c_str());
        if (inputs.tolerances)
            std::printf("  tolerances              %s\n",
                        predict::maker_tolerance_text(*inputs.tolerances,
                                                      std::vector<std::string>(at_least.begin(), at_least.end()),
                                                      predict::printed_extent_mm(design))
                            .c_str());
        for (const std::string& warning : inputs.warnings) std::printf("  warning                 %s\n", warning.c_str());
    });
}

}  // namespace rfd::cli
