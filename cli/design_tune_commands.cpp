// rfd design tune: a design's plane spacings chosen against the targets a maker names
// (tune/tune.hpp), written as a design file every other command reads as it is.

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/text.hpp"
#include "optics/design.hpp"
#include "tune/tune.hpp"

namespace rfd::cli {
namespace {

struct TuneOptions {
    std::string file;
    std::string out;
    std::vector<std::string> free;
    double range_mm = 10.0;
    std::vector<std::string> targets;
    std::vector<std::string> planes{"all"};
    double tolerance_scale = 1.0;
    std::string maximise = "efficiency_on_axis";
    double min_gap_mm = 0.0;
    int starts = 8;
    int evaluations = 200;
    std::uint64_t seed = 1;
    bool json = false;
};

tune::TuneSpec spec_from(const optics::Design& design, const TuneOptions& opt) {
    tune::TuneSpec spec = tune::default_spec(design, opt.range_mm, opt.min_gap_mm);
    if (!opt.free.empty()) {
        spec.free.clear();
        for (const auto& name : opt.free)
            spec.free.push_back(tune::free_spacing(design, name, opt.range_mm, opt.min_gap_mm));
    }
    spec.tolerance_scale = opt.tolerance_scale;
    for (const auto& text : opt.targets) spec.targets.push_back(tune::parse_target(text));
    if (opt.planes.size() == 1 && opt.planes[0] == "none")
        spec.planes.clear();
    else if (!(opt.planes.size() == 1 && opt.planes[0] == "all"))
        spec.planes = opt.planes;
    bool known = false;
    for (auto m : {tune::Measure::EfficiencyOnAxis, tune::Measure::EfficiencyAtHalfFov, tune::Measure::FieldOfView,
                   tune::Measure::EfficiencyMean})
        if (tune::to_string(m) == opt.maximise) {
            spec.maximise = m;
            known = true;
        }
    if (!known)
        throw InputError("--maximize '" + opt.maximise + "': expected one of " + tune::measure_names());
    spec.starts = opt.starts;
    spec.evaluations_per_start = opt.evaluations;
    spec.seed = opt.seed;
    tune::check_spec(design, spec);
    return spec;
}

std::string measure_line(const char* label, double before, double after, const char* unit, double scale) {
    return format_text("  %-26s %8.2f -> %8.2f %s\n", label, scale * before, scale * after, unit);
}

// What the tuner did, for the terminal and for the tuned file's header.
std::string report_text(const optics::Design& design, const tune::TuneSpec& spec, const tune::TuneResult& r,
                        const std::string& file) {
    std::string out;
    out += format_text("tuned %s: maximise %s", file.c_str(), std::string(tune::to_string(spec.maximise)).c_str());
    for (const auto& key : spec.planes) out += ", " + key + " in place";
    for (const auto& target : spec.targets) out += ", " + tune::to_string(target);
    out += "\n";
    out += format_text("  optimiser                  NLopt COBYLA, %d starts (seed %llu), %d evaluations\n",
                       spec.starts, static_cast<unsigned long long>(spec.seed), r.evaluations);
    out += measure_line("efficiency on axis", r.before.efficiency_on_axis, r.after.efficiency_on_axis, "%", 100);
    out += measure_line("efficiency at half the FOV", r.before.efficiency_at_half_fov, r.after.efficiency_at_half_fov,
                        "%", 100);
    out += measure_line("efficiency over the field", r.before.efficiency_mean, r.after.efficiency_mean, "%", 100);
    out += measure_line("field of view", r.before.field_of_view_deg, r.after.field_of_view_deg, "deg", 1);
    for (std::size_t k = 0; k < spec.free.size(); ++k)
        out += format_text("  spacing in front of %-6s %8.4f -> %8.4f mm\n", spec.free[k].plane.c_str(),
                           r.spacing_before[k], r.spacing_after[k]);
    for (std::size_t k = 1; k < design.planes.size(); ++k)
        out += format_text("  plane %-20s z %8.4f -> %8.4f mm (%+.4f)\n", design.planes[k].name.c_str(),
                           design.planes[k].z, r.design.planes[k].z, r.design.planes[k].z - design.planes[k].z);
    for (std::size_t k = 0; k < r.after.planes.size(); ++k) {
        const auto& b = r.before.planes[k];
        const auto& a = r.after.planes[k];
        out += format_text("  %s: %+.3f -> %+.3f mm from where the optics want it\n", a.description.c_str(),
                           b.plane_z - b.target_z, a.plane_z - a.target_z);
    }
    out += r.feasible ? "  every condition holds\n" : "  NOT every condition holds: see below\n";
    for (const auto& c : r.conditions)
        if (c.binding || c.slack < 0)
            out += format_text("  %s: %s (slack %.4g)\n", c.slack < 0 ? "violated" : "binds", c.name.c_str(), c.slack);
    out += format_text("  warnings                   %zu -> %zu\n", r.before.warnings.size(), r.after.warnings.size());
    for (const auto& w : r.after.warnings) out += "    " + w + "\n";
    return out;
}

nlohmann::json measures_json(const tune::Measures& m) {
    nlohmann::json planes = nlohmann::json::array();
    for (const auto& c : m.planes)
        planes.push_back({{"description", c.description},
                          {"miss_mm", std::isfinite(c.target_z) ? nlohmann::json(c.plane_z - c.target_z) : nlohmann::json()},
                          {"tolerance_mm", c.tolerance}});
    return {{"efficiency_on_axis", m.efficiency_on_axis},
            {"efficiency_at_half_fov", m.efficiency_at_half_fov},
            {"field_of_view_deg", m.field_of_view_deg},
            {"efficiency_mean", m.efficiency_mean},
            {"planes", planes},
            {"warnings", m.warnings}};
}

}  // namespace

void add_design_tune_command(CLI::App& design_cmd) {
    auto* cmd = design_cmd.add_subcommand(
        "tune", "Choose a design's plane spacings to meet targets (NLopt COBYLA) and write the tuned design file");
    auto opt = std::make_shared<TuneOptions>();
    cmd->add_option("DESIGN", opt->file, "Design TOML file")->required();
    cmd->add_option("--out", opt->out, "The tuned design file (the given one with new z_mm and a header)")->required();
    cmd->add_option("--free", opt->free,
                    "Planes whose spacing to the part in front may change; the planes behind move with it "
                    "(default: every plane but the first)")
        ->delimiter(',');
    cmd->add_option("--range", opt->range_mm, "How much longer each free spacing may grow, mm")
        ->check(CLI::Range(0.001, 1000.0));
    cmd->add_option("--target", opt->targets,
                    "A measure to keep: NAME>=VALUE or NAME<=VALUE (efficiency_on_axis, efficiency_at_half_fov "
                    "as fractions; field_of_view_deg); repeatable");
    cmd->add_option("--planes", opt->planes,
                    "Plane conditions to hold within design show's tolerance: all, none (what the parts allow "
                    "at best), or keys as design show names them, e.g. meso-focus,pattern-image")
        ->delimiter(',');
    cmd->add_option("--tolerance-scale", opt->tolerance_scale,
                    "Hold the planes within this fraction of the tolerance design show warns beyond")
        ->check(CLI::Range(0.01, 1.0));
    cmd->add_option("--maximize", opt->maximise, "The measure to make as large as the targets allow");
    cmd->add_option("--min-gap", opt->min_gap_mm, "Least free spacing, mm (0: parts may touch)")
        ->check(CLI::Range(0.0, 100.0));
    cmd->add_option("--starts", opt->starts, "COBYLA runs: from the design and from seeded points")
        ->check(CLI::Range(1, 1000));
    cmd->add_option("--evaluations", opt->evaluations, "Evaluations per run")->check(CLI::Range(10, 100000));
    cmd->add_option("--seed", opt->seed, "Seed of the starting points");
    cmd->add_flag("--json", opt->json, "Machine-readable report on stdout");
    cmd->callback([opt] {
        const optics::Design design = optics::load_design(opt->file);
        const tune::TuneSpec spec = spec_from(design, *opt);
        const tune::TuneResult result = tune::tune_design(design, spec);
        const std::string report = report_text(design, spec, result, opt->file);
        if (!result.feasible) {
            // Nothing is written: a design file that breaks the conditions is no answer.
            std::fputs(report.c_str(), stdout);
            throw Error("design tune: no spacings within their ranges (up to " + format_number(opt->range_mm) +
                        " mm longer) meet every condition (the report above names those violated); widen --range, "
                        "free more planes or relax a --target");
        }
        const std::string header = "Tuned by `rfd design tune` from " + opt->file + ".\n" + report;
        write_text_file(opt->out, tune::tuned_design_text(read_text_file(opt->file), design, result, header));
        if (opt->json) {
            nlohmann::json conditions = nlohmann::json::array();
            for (const auto& c : result.conditions)
                conditions.push_back({{"name", c.name}, {"slack", c.slack}, {"binding", c.binding}});
            nlohmann::json planes = nlohmann::json::array();
            for (std::size_t k = 0; k < spec.free.size(); ++k)
                planes.push_back({{"plane", spec.free[k].plane},
                                  {"spacing_before_mm", result.spacing_before[k]},
                                  {"spacing_after_mm", result.spacing_after[k]}});
            nlohmann::json z = nlohmann::json::object();
            for (const auto& plane : result.design.planes) z[plane.name] = plane.z;
            const nlohmann::json out{{"design", opt->file},
                                     {"out", opt->out},
                                     {"maximize", tune::to_string(spec.maximise)},
                                     {"evaluations", result.evaluations},
                                     {"free", planes},
                                     {"z_mm", z},
                                     {"before", measures_json(result.before)},
                                     {"after", measures_json(result.after)},
                                     {"conditions", conditions}};
            std::printf("%s\n", out.dump(2).c_str());
        } else {
            std::fputs(report.c_str(), stdout);
        }
    });
}

}  // namespace rfd::cli
