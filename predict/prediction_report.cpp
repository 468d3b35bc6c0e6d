#include "predict/prediction_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/json.hpp"
#include "core/text.hpp"
#include "core/units.hpp"

namespace rfd::predict {
namespace {

nlohmann::json light_checks_json(const std::vector<LightCheck>& checks) {
    nlohmann::json out = nlohmann::json::array();
    for (const LightCheck& c : checks)
        out.push_back({{"display_deg", {c.display_theta_deg, c.display_phi_deg}},
                       {"field_deg", {c.field_theta_deg, c.field_phi_deg}},
                       {"angle_to_axis_deg", c.display_theta_deg},
                       {"wrap_over_deg", json_or_null(c.wrap_over_deg)},
                       {"crosstalk_onset_deg", json_or_null(c.crosstalk_deg)},
                       {"warning", c.warning()}});
    return out;
}

void light_check_line(std::string& text, const std::string& light, const LightCheck& c) {
    text += format_text("               %s: display %s, field %s; %s deg from the axis (field of view to %s, crosstalk from "
         "%s deg along its azimuth)\n",
         light.c_str(), (format_fixed(c.display_theta_deg, 1) + "," + format_fixed(c.display_phi_deg, 1)).c_str(),
         (format_fixed(c.field_theta_deg, 1) + "," + format_fixed(c.field_phi_deg, 1)).c_str(),
         format_fixed(c.display_theta_deg, 1).c_str(), c.wrap_over_deg ? format_fixed(*c.wrap_over_deg, 1).c_str() : "89+",
         c.crosstalk_deg ? format_fixed(*c.crosstalk_deg, 1).c_str() : "89+");
}

}  // namespace

nlohmann::json environment_json(const std::string& file, const EnvironmentSampling& sampling) {
    return {{"file", file},
            {"size", {sampling.width, sampling.height}},
            {"sampled_size", {sampling.sampled_width, sampling.sampled_height}},
            {"box_filter", sampling.reduction},
            {"reason", sampling.reason},
            {"directions", sampling.directions},
            {"directions_in_front", sampling.in_front}};
}

std::string environment_line(const std::string& file, const EnvironmentSampling& sampling) {
    std::string text;
    text += format_text("  envmap       %s: %d x %d", file.c_str(), sampling.width, sampling.height);
    if (sampling.reduction > 1)
        text += format_text(", sampled at %d x %d (box filter %d: %s)", sampling.sampled_width, sampling.sampled_height,
             sampling.reduction, sampling.reason.c_str());
    text += format_text("; %zu direction(s) light the display from behind, %zu from the front (dropped)\n", sampling.directions,
         sampling.in_front);
    return text;
}

nlohmann::json to_json(const DiffuserPredictionReport& report) {
    const optics::DiffuserImage& result = *report.result;
    nlohmann::json summary = {
        {"out", report.out},
        {"model", std::string(optics::to_string(report.choice.model))},
        {"model_choice", report.model_choice},
        {"paraxial_error_dots", json_or_null(report.choice.paraxial_error_dots)},
        {"diffraction", report.choice.diffraction},
        {"diffraction_lobe_dots", json_or_null(report.choice.diffraction_lobe_dots)},
        {"lights", report.lights.size()},
        {"frame", std::string(name_of(kLightFrameNames, report.frame))},
        {"light_checks", light_checks_json(report.checks)},
        {"directions", result.directions},
        {"rays_per_direction", result.rays_per_direction},
        {"rays", result.rays},
        {"rays_lost", result.lost},
        {"rays_crossed", result.crossed},
        {"optical_efficiency", result.optical_efficiency},
        {"pattern_efficiency", result.pattern_efficiency},
        {"pixels", {result.image.width(), result.image.height()}},
        {"pixel_mm", result.pixel_mm},
        {"exposure_stops", report.exposure_stops},
        {"seconds", report.seconds}};
    nlohmann::json front = nlohmann::json::array();
    for (const optics::FrontLightContrast& c : report.contrast.with_front)  // JSON has no infinity: null
        front.push_back({{"front_ratio", c.front_ratio},
                         {"contrast", std::isfinite(c.contrast) ? nlohmann::json(c.contrast) : nlohmann::json()}});
    summary["contrast"] = {{"white", report.contrast.white},
                           {"black", report.contrast.black},
                           {"transmissivity", report.contrast.transmissivity},
                           {"diffuser_transmittance", report.diffuser.transmittance},
                           {"diffuser_reflectance", report.diffuser.reflectance},
                           {"with_front_light", front}};
    if (!report.envmap.empty()) summary["envmap"] = environment_json(report.envmap, report.sampling);
    return summary;
}

std::string report_text(const DiffuserPredictionReport& report) {
    const optics::DiffuserImage& result = *report.result;
    const optics::PictureContrast& contrast = report.contrast;
    std::string text;
    text += format_text("%s: %d x %d pixels of %.4f mm, what '%s' shows\n", report.out.c_str(), result.image.width(),
         result.image.height(), result.pixel_mm, report.design.c_str());
    text += format_text("  model        %s%s (%s; paraxial error up to %.2f dots, diffraction's central lobe %.2f dots, "
                        "tolerance %.2f)\n",
         std::string(optics::to_string(report.choice.model)).c_str(),
         report.choice.diffraction ? " and diffraction" : "",
         report.model_choice == "auto" ? "chosen automatically" : "as asked",
         report.choice.paraxial_error_dots.value_or(0.0), report.choice.diffraction_lobe_dots.value_or(0.0),
         report.tolerance_dots);
    text += format_text("  light        %zu light(s)%s, %zu direction(s) sampled, %zu ray(s) per direction and lenslet, %zu rays\n",
         report.lights.size(), report.envmap.empty() ? "" : " and an environment map", result.directions,
         result.rays_per_direction, result.rays);
    for (std::size_t k = 0; k < report.checks.size(); ++k) light_check_line(text, report.lights[k], report.checks[k]);
    if (!report.envmap.empty()) text += (environment_line(report.envmap, report.sampling));
    text += format_text("  efficiency   %.1f %% of the light entering the lenslets reaches the diffuser; "
         "%.1f / %.1f / %.1f %% through the pattern (R/G/B)\n",
         100 * result.optical_efficiency, 100 * result.pattern_efficiency[0], 100 * result.pattern_efficiency[1],
         100 * result.pattern_efficiency[2]);
    text += format_text("  crosstalk    %.2f %% of the rays reach the diffuser through a neighbouring lenslet\n",
         result.rays ? 100.0 * static_cast<double>(result.crossed) / static_cast<double>(result.rays) : 0.0);
    text += format_text("  contrast     white %.4f, black %.4f (99th / 1st percentile over the lenslets); %.1f %% as bright "
         "as the back light through the diffuser\n",
         contrast.white, contrast.black, 100 * contrast.transmissivity);
    for (const optics::FrontLightContrast& c : contrast.with_front) {
        if (std::isfinite(c.contrast))
            text += format_text("               %.1f : 1 with front / back light %g%s\n", c.contrast, c.front_ratio,
                 c.front_ratio == 0.0 ? " (dark room)" : "");
        else
            text += format_text("               unbounded with front / back light %g%s (the blacks are black)\n", c.front_ratio,
                 c.front_ratio == 0.0 ? " (dark room)" : "");
    }
    text += format_text("  time         %.2f s\n", report.seconds);
    return text;
}

nlohmann::json to_json(const ObserverPredictionReport& report) {
    const optics::AngularDisplayOutput& result = *report.result;
    nlohmann::json losses = nlohmann::json::object();
    for (const auto& [surface, fraction] : result.lost_fraction) losses[surface] = fraction;
    nlohmann::json summary = {
        {"out", report.written},
        {"design_kind", report.design_kind},
        {"model", std::string(optics::to_string(report.choice.model))},
        {"model_choice", report.model_choice},
        {"diffraction", report.choice.diffraction},
        {"lights", report.lights},
        {"views", report.views},
        {"directions", result.directions},
        {"rays", result.rays},
        {"rays_lost", result.lost},
        {"rays_crossed", result.crossed},
        {"optical_efficiency", result.optical_efficiency},
        {"pattern_efficiency", result.pattern_efficiency},
        {"crosstalk_fraction", result.crossed_fraction},
        {"lost_fraction", losses},
        {"meso_pixels", {report.macro_x * report.lattice_x, report.macro_y * report.lattice_y}},
        {"macro_grid", {report.macro_x, report.macro_y}},
        {"kernel_deg", radians_to_degrees(std::atan(result.kernel_half_tan))},
        {"distribution_half_angle_deg", radians_to_degrees(std::atan(result.distribution_half_tan))},
        {"reference_radiance_per_sr", result.reference_radiance_per_sr},
        {"seconds", report.seconds}};
    if (!report.envmap.empty()) summary["envmap"] = environment_json(report.envmap, report.sampling);
    return summary;
}

std::string report_text(const ObserverPredictionReport& report) {
    const optics::AngularDisplayOutput& result = *report.result;
    const double rays = static_cast<double>(std::max<std::size_t>(result.rays, 1));
    std::string text;
    text += format_text("%s: what '%s' sends toward %zu viewpoint(s), %d x %d meso-pixels (%d x %d macro-pixels)\n",
         report.written.front().c_str(), report.design.c_str(), result.views.size(), report.macro_x * report.lattice_x,
         report.macro_y * report.lattice_y, report.macro_x, report.macro_y);
    text += format_text("  model        %s (%s)\n", std::string(optics::to_string(report.choice.model)).c_str(),
         report.choice.reason.c_str());
    text += format_text("  light        %zu light(s)%s, %zu direction(s) sampled, %zu rays per macro-pixel\n", report.lights,
         report.envmap.empty() ? "" : " and an environment map", result.directions, result.rays);
    if (!report.envmap.empty()) text += (environment_line(report.envmap, report.sampling));
    text += format_text("  efficiency   %.1f %% of the light entering the main lens leaves the display; "
         "%.1f / %.1f / %.1f %% through the pattern (R/G/B)\n",
         100 * result.optical_efficiency, 100 * result.pattern_efficiency[0], 100 * result.pattern_efficiency[1],
         100 * result.pattern_efficiency[2]);
    text += format_text("  crosstalk    %.2f %% of the light leaves through a neighbouring lenslet (%.2f %% of the rays)\n",
         100 * result.crossed_fraction, 100.0 * static_cast<double>(result.crossed) / rays);
    for (const auto& [surface, fraction] : result.lost_fraction)
        text += format_text("  lost         %5.1f %% at %s\n", 100 * fraction, surface.c_str());
    text += format_text("  kernel       %.2f deg over output directions; 1.0 = %.4g /sr per unit irradiance\n",
         radians_to_degrees(std::atan(result.kernel_half_tan)), result.reference_radiance_per_sr);
    text += format_text("  time         %.2f s\n", report.seconds);
    return text;
}

}  // namespace rfd::predict
