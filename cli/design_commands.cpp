// rfd design show and rfd optics chart: a display design's summary and its
// speed-versus-accuracy chart (paraxial against exact).

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/files.hpp"
#include "core/plot.hpp"
#include "core/text.hpp"
#include "core/units.hpp"
#include "optics/accuracy_chart.hpp"
#include "optics/analysis.hpp"
#include "optics/design.hpp"
#include "optics/diffraction.hpp"

namespace rfd::cli {
namespace {

nlohmann::json conjugates_json(const optics::DesignSummary& s) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& c : s.conjugates)
        out.push_back({{"key", c.key},
                       {"description", c.description},
                       {"plane_z_mm", c.plane_z},
                       {"target_z_mm", std::isfinite(c.target_z) ? nlohmann::json(c.target_z) : nlohmann::json()},
                       {"magnification", std::isfinite(c.magnification) ? nlohmann::json(c.magnification) : nlohmann::json()}});
    return out;
}

nlohmann::json losses_json(const optics::DesignSummary& s) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& loss : s.losses)
        out.push_back({{"angle_deg", loss.angle_deg},
                       {"surface", loss.surface},
                       {"status", optics::to_string(loss.status)},
                       {"fraction", loss.fraction}});
    return out;
}

nlohmann::json diffraction_json(const optics::DiffractionEstimate& e) {
    nlohmann::json lobe = nlohmann::json::object();
    for (std::size_t k = 0; k < optics::kDiffractionWavelengthsMm.size(); ++k)
        lobe[format_text("%.0f", optics::kDiffractionWavelengthsMm[k] * 1e6)] = 1000.0 * e.lobe_radius_mm[k];
    return {{"element", e.element},
            {"focal_length_mm", e.focal_length},
            {"aperture_mm", {e.aperture_x, e.aperture_y}},
            {"lobe_radius_um", lobe},
            {"lobe_dots_650nm", {e.lobe_dots().x(), e.lobe_dots().y()}},
            {"critical_dot_um", 1000.0 * e.critical_dot_mm()},
            {"critical_dpi", 25.4 / e.critical_dot_mm()},
            {"one_dot_feature_spread_mm", e.feature_spread_mm(e.dot_mm.x())}};
}

std::string diffraction_text(const optics::DiffractionEstimate& e, double spot_rms_um, bool observer_variant) {
    std::string out;
    out += format_text("  diffraction               central lobe %.2f / %.2f / %.2f um on the pattern at 450 / 550 / 650 nm\n",
                       1000 * e.lobe_radius_mm[0], 1000 * e.lobe_radius_mm[1], 1000 * e.lobe_radius_mm[2]);
    out += format_text("                            (%s: f %.3f mm, cell %.3f x %.3f mm): %.3f x %.3f print dots at 650 nm\n",
                       e.element.c_str(), e.focal_length, e.aperture_x, e.aperture_y, e.lobe_dots().x(),
                       e.lobe_dots().y());
    out += format_text("                            exceeds a print dot for dots under %.2f um (above %.0f dpi)", 1000 * e.critical_dot_mm(),
                       25.4 / e.critical_dot_mm());
    if (observer_variant)
        out += format_text(";\n                            a one-dot feature spreads its light +-%.3f mm on the projection "
                           "lenslets (cell %.3f mm wide)\n",
                           e.feature_spread_mm(e.dot_mm.x()), e.aperture_x);
    else
        out += format_text("; geometric RMS spot %.1f um\n", spot_rms_um);
    return out;
}

nlohmann::json to_json(const optics::DesignSummary& s) {
    auto pairs = [](const auto& list) {
        nlohmann::json out = nlohmann::json::object();
        for (const auto& [name, value] : list) out[name] = json_or_null(value);
        return out;
    };
    return {{"name", s.name},
            {"kind", s.kind},
            {"lattice", s.lattice},
            {"pitch_x_mm", s.pitch_x},
            {"row_spacing_mm", s.pitch_y},
            {"count", {s.count_x, s.count_y}},
            {"macro_grid", s.macro ? nlohmann::json{{"count", {s.macro->count_x, s.macro->count_y}},
                                                    {"pitch_mm", {s.macro->pitch_x, s.macro->pitch_y}}}
                                   : nlohmann::json()},
            {"focal_length_nominal_mm", s.focal_length_nominal},
            {"focal_length_paraxial_mm", s.focal_length_paraxial},
            {"printer_dpi", {s.dpi_x, s.dpi_y}},
            {"print_pixels_per_lenslet", s.directions_per_lenslet},
            {"angular_step_deg", {s.angular_step_x_deg, s.angular_step_y_deg}},
            {"wrap_over_paraxial_deg", pairs(s.wrap_over_paraxial_deg)},
            {"wrap_over_exact_deg", pairs(s.wrap_over_exact_deg)},
            {"crosstalk_begins_exact_deg", pairs(s.crosstalk_exact_deg)},
            {"field_of_view_deg", json_or_null(s.field_of_view_deg)},
            {"efficiency_on_axis", s.efficiency_on_axis},
            {"efficiency_at_half_fov", s.efficiency_at_half_fov},
            {"efficiency_with_fresnel_on_axis", s.efficiency_fresnel_on_axis},
            {"efficiency_with_fresnel_at_half_fov", s.efficiency_fresnel_at_half_fov},
            {"losses", losses_json(s)},
            {"spot_rms_on_axis_um", s.spot_rms_on_axis_um},
            {"spot_rms_at_half_fov_um", s.spot_rms_at_half_fov_um},
            {"focus_error_mm", s.focus_error_mm},
            {"conjugates", conjugates_json(s)},
            {"warnings", s.warnings}};
}

std::string summary_text(const optics::DesignSummary& s, const optics::DiffractionEstimate& diffraction,
                         bool observer_variant) {
    std::string out;
    out += format_text("%s  (Design %s)\n", s.name.c_str(), s.kind.c_str());
    out += format_text("  lattice                   %s, %d x %d lenslets\n", s.lattice.c_str(), s.count_x, s.count_y);
    out += format_text("  pitch                     %.4f mm (rows %.4f mm apart)\n", s.pitch_x, s.pitch_y);
    if (s.macro)
        out += format_text("  macro-pixels              %d x %d Design III cells, %.2f mm x %.2f mm apart\n",
                           s.macro->count_x, s.macro->count_y, s.macro->pitch_x, s.macro->pitch_y);
    out += format_text("  focal length              %.4f mm paraxial (maker: %.4g mm)\n", s.focal_length_paraxial,
                       s.focal_length_nominal);
    out += format_text("  printer                   %.0f x %.0f dpi\n", s.dpi_x, s.dpi_y);
    if (observer_variant) {
        out += format_text("  print pixels per meso-pixel %.0f (output directions)\n", s.directions_per_lenslet);
        out += format_text("  incident angle per meso-pixel %.3f deg (x), %.3f deg (y)\n", s.angular_step_x_deg,
                           s.angular_step_y_deg);
    } else {
        out += format_text("  directions per lenslet    %.0f (print pixels under one cell)\n",
                           s.directions_per_lenslet);
        out += format_text("  angular step (on axis)    %.4f deg per pixel in x, %.4f deg in y\n",
                           s.angular_step_x_deg, s.angular_step_y_deg);
    }
    out += format_text("  %s (paraxial / exact chief ray):\n",
                       observer_variant ? "edge of the meso-pixel array" : "wrap-over angle");
    // An angle, or where nothing happened up to the searched limit.
    auto angle_text = [](const std::optional<double>& angle) {
        return angle ? format_text("%6.2f deg", *angle)
                     : format_text("none up to %.0f deg", optics::kWrapOverSearchLimitDeg);
    };
    for (std::size_t k = 0; k < s.wrap_over_exact_deg.size(); ++k)
        out += format_text("    along %-12s          %s / %s\n", s.wrap_over_exact_deg[k].first.c_str(),
                           angle_text(s.wrap_over_paraxial_deg[k].second).c_str(),
                           angle_text(s.wrap_over_exact_deg[k].second).c_str());
    for (const auto& [name, angle] : s.crosstalk_exact_deg)
        out += format_text("  crosstalk begins (exact, full bundle) along %-10s %s\n", name.c_str(),
                           angle_text(angle).c_str());
    if (s.field_of_view_deg)
        out += format_text("  field of view             %.2f deg (full cone, exact)\n", *s.field_of_view_deg);
    else
        out += format_text("  field of view             no wrap-over up to %.0f deg from the axis\n",
                           optics::kWrapOverSearchLimitDeg);
    out += format_text("  light efficiency          %.1f %% on axis, %.1f %% at half the field of view\n",
                       100 * s.efficiency_on_axis, 100 * s.efficiency_at_half_fov);
    out += "                            (rays reaching the last surface of the optics)\n";
    out += format_text("    with Fresnel reflections  %.1f %% on axis, %.1f %% at half the field of view (uncoated)\n",
                       100 * s.efficiency_fresnel_on_axis, 100 * s.efficiency_fresnel_at_half_fov);
    for (const auto& loss : s.losses)
        out += format_text("    at %5.2f deg: %5.1f %% lost at '%s' (%s)\n", loss.angle_deg, 100 * loss.fraction,
                           loss.surface.c_str(), std::string(optics::to_string(loss.status)).c_str());
    out += format_text("  RMS spot on encoding plane %.2f um on axis, %.2f um at half the field of view\n",
                       s.spot_rms_on_axis_um, s.spot_rms_at_half_fov_um);
    out += format_text("  encoding plane vs focus   %+.4f mm\n", s.focus_error_mm);
    for (const auto& check : s.conjugates) {
        out += format_text("  %s [%s]\n      plane at z = %.4f mm, optics want z = %.4f mm (%+.4f mm)",
                           check.description.c_str(), check.key.c_str(), check.plane_z, check.target_z, check.plane_z - check.target_z);
        if (std::isfinite(check.magnification)) out += format_text(", magnification %.4f", check.magnification);
        out += "\n";
    }
    out += diffraction_text(diffraction, s.spot_rms_on_axis_um, observer_variant);
    if (s.warnings.empty()) out += "  design rules              no warnings\n";
    for (const auto& warning : s.warnings) out += format_text("  warning: %s\n", warning.c_str());
    return out;
}

}  // namespace

void add_design_commands(CLI::App& app) {
    auto* design_cmd = app.add_subcommand("design", "Display designs (Designs I-IV)");
    design_cmd->require_subcommand(1);
    auto* cmd = design_cmd->add_subcommand(
        "show", "Summary of a display design: pitch, directions, wrap-over, field of view, warnings");
    struct Options {
        std::string file;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->file, "Design TOML file")->required();
    cmd->add_flag("--json", opt->json, "Machine-readable output");
    cmd->callback([opt] {
        const auto design = optics::load_design(opt->file);
        const optics::DesignOptics optics(design);
        const auto summary = optics::summarise(optics);
        // Not in summarise(): `design tune` calls that a thousand times, this costs three FFTs.
        const auto diffraction = optics::estimate_diffraction(optics);
        if (opt->json) {
            nlohmann::json out = to_json(summary);
            out["diffraction"] = diffraction_json(diffraction);
            std::printf("%s\n", out.dump(2).c_str());
        } else {
            std::fputs(summary_text(summary, diffraction, optics::is_observer_variant(design.kind)).c_str(), stdout);
        }
    });
    add_design_tune_command(*design_cmd);
    add_design_advise_command(*design_cmd);
}

void add_chart_command(CLI::App& optics_cmd) {
    auto* cmd = optics_cmd.add_subcommand(
        "chart", "Speed-versus-accuracy chart: paraxial error against exact, per incident angle");
    struct Options {
        std::string file;
        std::string out;
        int steps = 120;
        double max_angle = 0.0;
        std::size_t timing_rays = 400000;
        bool no_timing = false;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->file, "Design TOML file")->required();
    cmd->add_option("--out", opt->out, "Output directory")->required();
    cmd->add_option("--steps", opt->steps, "Angles per sweep")->check(CLI::Range(4, 100000));
    cmd->add_option("--max-angle", opt->max_angle,
                    "Largest incident angle in degrees (default: 1.25 x the exact wrap-over angle)")
        ->check(CLI::Range(0.0, 89.0));
    cmd->add_option("--timing-rays", opt->timing_rays, "Rays per model for the rays/s figure")
        ->check(CLI::Range(1000, 100000000));
    cmd->add_flag("--no-timing", opt->no_timing,
                  "Skip the rays/s measurement (outputs are then byte-identical run to run)");
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        const auto design = optics::load_design(opt->file);
        const optics::DesignOptics optics(design);
        optics::ModelAccuracySettings settings;
        settings.steps = opt->steps;
        settings.max_angle_deg = opt->max_angle;
        settings.timing_rays = opt->no_timing ? std::nullopt : std::optional(opt->timing_rays);
        const optics::ModelAccuracy run = optics::chart_model_accuracy(optics, settings);
        const nlohmann::json summary = optics::write_model_accuracy(opt->out, run);
        if (opt->json)
            std::printf("%s\n", summary.dump(2).c_str());
        else
            std::fputs(optics::model_accuracy_text(run, opt->out).c_str(), stdout);
    });
}

}  // namespace rfd::cli
