#include "predict/summaries.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/files.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "optics/tolerance.hpp"
#include "predict/compare.hpp"
#include "predict/verdict.hpp"

namespace rfd::predict {
namespace {

using nlohmann::json;

// An optional number as JSON: null when absent or not finite (JSON has no NaN).
json number_or_null(const std::optional<double>& value) {
    return value && std::isfinite(*value) ? json(*value) : json(nullptr);
}

std::optional<double> optional_number(const json& object, const char* key) {
    const json& value = object.at(key);
    if (value.is_null()) return std::nullopt;
    return value.get<double>();
}

template <class T>
void read(const json& object, const char* key, T& value) {
    object.at(key).get_to(value);
}

// Running min and mean over the figures of a set of directions.
struct Accumulator {
    int count = 0;
    double min = HUGE_VAL, sum = 0.0;
    void add(const std::optional<double>& value) {
        if (!value) return;
        ++count;
        min = std::min(min, *value);
        sum += *value;
    }
    std::optional<double> minimum() const { return count ? std::optional<double>(min) : std::nullopt; }
    std::optional<double> mean() const { return count ? std::optional<double>(sum / count) : std::nullopt; }
};

PsnrFigures figures_over(const std::vector<const CompareDirection*>& directions) {
    PsnrFigures figures;
    figures.count = static_cast<int>(directions.size());
    Accumulator whole, fitted, cell;
    for (const CompareDirection* d : directions) {
        whole.add(d->psnr_db);
        fitted.add(d->psnr_fitted_db);
        cell.add(d->psnr_cell_db);
    }
    figures.min_psnr_db = whole.minimum();
    figures.mean_psnr_db = whole.mean();
    figures.min_psnr_fitted_db = fitted.minimum();
    figures.mean_psnr_fitted_db = fitted.mean();
    figures.min_psnr_cell_db = cell.minimum();
    return figures;
}

}  // namespace

std::optional<double> psnr_against_field_db(double mse, double field_peak) {
    if (!(field_peak > 0.0) || !std::isfinite(mse) || mse < 0.0) return std::nullopt;
    if (mse == 0.0) return optics::kPsnrCeilingDb;
    return std::min(optics::kPsnrCeilingDb, 10.0 * std::log10(field_peak * field_peak / mse));
}

double field_peak_of(const std::vector<DirectionComparison>& results) {
    double peak = 0.0;
    for (const DirectionComparison& r : results) peak = std::max(peak, r.comparison.peak);
    return peak;
}

CompareSummary summarise_comparison(const std::vector<DirectionComparison>& results,
                                    const std::vector<std::string>& images) {
    RFD_CHECK(images.size() == results.size());
    CompareSummary summary;
    summary.field_peak = field_peak_of(results);
    std::vector<const CompareDirection*> in_fov, clean;
    for (std::size_t k = 0; k < results.size(); ++k) {
        const DirectionComparison& r = results[k];
        const SphericalAngles a = angles_of(r.field_direction);
        CompareDirection d;
        d.image = images[k];
        d.field_theta_deg = radians_to_degrees(a.theta);
        d.field_phi_deg = radians_to_degrees(a.phi);
        d.display_angle_deg = r.display_angle_deg;
        d.inside_fov = r.inside_field_of_view;
        d.crosstalk_free = r.crosstalk_free;
        d.efficiency = r.efficiency;
        d.peak = r.comparison.peak;
        d.mse = r.comparison.mse;
        d.psnr_db = psnr_against_field_db(r.comparison.mse, summary.field_peak);
        if (std::isfinite(r.comparison.psnr_db)) d.psnr_own_peak_db = r.comparison.psnr_db;
        d.fitted_gain = r.comparison.fitted_gain;
        d.psnr_fitted_db = psnr_against_field_db(r.comparison.fitted_mse, summary.field_peak);
        d.psnr_cell_db = psnr_against_field_db(r.cell_comparison.mse, summary.field_peak);
        d.rays = static_cast<long long>(r.rays);
        summary.directions.push_back(std::move(d));
    }
    for (const CompareDirection& d : summary.directions) {
        if (d.inside_fov) in_fov.push_back(&d);
        if (d.crosstalk_free) clean.push_back(&d);
    }
    summary.in_fov = figures_over(in_fov);
    summary.crosstalk_free = figures_over(clean);
    if (!results.empty()) {
        summary.core_fraction = results.front().core.fraction;
        summary.core_magnification = results.front().core.magnification;
    }
    return summary;
}

VerdictReport verdict_report(const Verdict& v, const std::vector<std::string>& at_least) {
    VerdictReport report;
    report.design = v.inputs.design;
    report.call = std::string(to_string(v.call));
    report.reason = v.reason;
    report.line = v.line();
    report.field_call = std::string(to_string(v.on_field.call));
    report.field_line = v.on_field.line();
    report.design_call = std::string(to_string(v.on_design.call));
    report.design_line = v.on_design.line();
    report.psnr_mean_in_fov_db = v.psnr_mean_in_fov_db;
    report.psnr_min_in_fov_db = v.psnr_min_in_fov_db;
    report.psnr_mean_crosstalk_free_db = v.psnr_mean_crosstalk_free_db;
    report.directions_in_fov = v.directions_in_fov;
    report.directions_crosstalk_free = v.directions_crosstalk_free;
    report.field_of_view_deg = v.inputs.field_of_view_deg;
    report.crosstalk_free_cone_deg = v.inputs.crosstalk_free_cone_deg;
    if (const auto& t = v.inputs.tolerances)
        report.tolerances = VerdictReport::Tolerances{t->shift_mm, t->rotation_deg, t->pitch_ppm, t->spacer_mm, at_least};
    report.warnings = v.inputs.warnings;
    return report;
}

void to_json(json& j, const CompareDirection& d) {
    j = {{"image", d.image},
         {"field_theta_deg", d.field_theta_deg},
         {"field_phi_deg", d.field_phi_deg},
         {"display_angle_deg", d.display_angle_deg},
         {"inside_fov", d.inside_fov},
         {"crosstalk_free", d.crosstalk_free},
         {"efficiency", d.efficiency},
         {"peak", d.peak},
         {"mse", d.mse},
         {"psnr_db", number_or_null(d.psnr_db)},
         {"psnr_own_peak_db", number_or_null(d.psnr_own_peak_db)},
         {"fitted_gain", d.fitted_gain},
         {"psnr_fitted_db", number_or_null(d.psnr_fitted_db)},
         {"psnr_cell_db", number_or_null(d.psnr_cell_db)},
         {"rays", d.rays}};
}

void from_json(const json& j, CompareDirection& d) {
    read(j, "image", d.image);
    read(j, "field_theta_deg", d.field_theta_deg);
    read(j, "field_phi_deg", d.field_phi_deg);
    read(j, "display_angle_deg", d.display_angle_deg);
    read(j, "inside_fov", d.inside_fov);
    read(j, "crosstalk_free", d.crosstalk_free);
    read(j, "efficiency", d.efficiency);
    read(j, "peak", d.peak);
    read(j, "mse", d.mse);
    d.psnr_db = optional_number(j, "psnr_db");
    d.psnr_own_peak_db = optional_number(j, "psnr_own_peak_db");
    read(j, "fitted_gain", d.fitted_gain);
    d.psnr_fitted_db = optional_number(j, "psnr_fitted_db");
    d.psnr_cell_db = optional_number(j, "psnr_cell_db");
    read(j, "rays", d.rays);
}

void to_json(json& j, const AccuracyRecord& a) {
    json per_direction = json::array();
    for (const AccuracyRecord::Direction& d : a.per_direction)
        per_direction.push_back({{"display_angle_deg", d.display_angle_deg},
                                 {"psnr_db", number_or_null(d.psnr_db)},
                                 {"fitted_psnr_db", number_or_null(d.fitted_psnr_db)}});
    j = {{"model", a.model},
         {"rays_per_side", a.rays_per_side},
         {"rays", a.rays},
         {"seconds", a.seconds},
         {"mse", a.mse},
         {"psnr_db", number_or_null(a.psnr_db)},
         {"worst_psnr_db", number_or_null(a.worst_psnr_db)},
         {"fitted_psnr_db", number_or_null(a.fitted_psnr_db)},
         {"per_direction", per_direction}};
}

void from_json(const json& j, AccuracyRecord& a) {
    read(j, "model", a.model);
    read(j, "rays_per_side", a.rays_per_side);
    read(j, "rays", a.rays);
    read(j, "seconds", a.seconds);
    read(j, "mse", a.mse);
    a.psnr_db = optional_number(j, "psnr_db");
    a.worst_psnr_db = optional_number(j, "worst_psnr_db");
    a.fitted_psnr_db = optional_number(j, "fitted_psnr_db");
    a.per_direction.clear();
    for (const json& d : j.at("per_direction"))
        a.per_direction.push_back({d.at("display_angle_deg").get<double>(), optional_number(d, "psnr_db"),
                                   optional_number(d, "fitted_psnr_db")});
}

void to_json(json& j, const CompareSummary& s) {
    j = {{"design", s.design},
         {"pattern", s.pattern},
         {"field", s.field},
         {"model", s.model},
         {"model_choice", s.model_choice},
         {"paraxial_error_dots", number_or_null(s.paraxial_error_dots)},
         {"rays_per_side", s.rays_per_side},
         {"lenslets", s.lenslets},
         {"display_range_deg", s.display_range_deg},
         {"field_peak", s.field_peak},
         {"psnr", "every psnr_db is 10 log10(field_peak^2 / mse), field_peak the reference's brightest value over "
                  "the directions, capped at 100 dB; psnr_own_peak_db uses the direction's own peak"},
         {"reference_scale", "the display's simulated response to a clear print under the same light (not fitted)"},
         {"directions", s.directions},
         {"macro_pixel_core", {{"fraction", s.core_fraction}, {"magnification", s.core_magnification}}},
         {"inside_fov", s.in_fov.count},
         {"min_psnr_in_fov_db", number_or_null(s.in_fov.min_psnr_db)},
         {"mean_psnr_in_fov_db", number_or_null(s.in_fov.mean_psnr_db)},
         {"min_psnr_fitted_in_fov_db", number_or_null(s.in_fov.min_psnr_fitted_db)},
         {"mean_psnr_fitted_in_fov_db", number_or_null(s.in_fov.mean_psnr_fitted_db)},
         {"min_psnr_cell_in_fov_db", number_or_null(s.in_fov.min_psnr_cell_db)},
         {"crosstalk_free", s.crosstalk_free.count},
         {"min_psnr_crosstalk_free_db", number_or_null(s.crosstalk_free.min_psnr_db)},
         {"mean_psnr_crosstalk_free_db", number_or_null(s.crosstalk_free.mean_psnr_db)},
         {"min_psnr_fitted_crosstalk_free_db", number_or_null(s.crosstalk_free.min_psnr_fitted_db)},
         {"mean_psnr_fitted_crosstalk_free_db", number_or_null(s.crosstalk_free.mean_psnr_fitted_db)},
         {"min_psnr_cell_crosstalk_free_db", number_or_null(s.crosstalk_free.min_psnr_cell_db)},
         {"accuracy_directions", s.accuracy_directions},
         {"accuracy", s.accuracy}};
}

void from_json(const json& j, CompareSummary& s) {
    read(j, "design", s.design);
    read(j, "pattern", s.pattern);
    read(j, "field", s.field);
    read(j, "model", s.model);
    read(j, "model_choice", s.model_choice);
    s.paraxial_error_dots = optional_number(j, "paraxial_error_dots");
    read(j, "rays_per_side", s.rays_per_side);
    read(j, "lenslets", s.lenslets);
    read(j, "display_range_deg", s.display_range_deg);
    read(j, "field_peak", s.field_peak);
    read(j, "directions", s.directions);
    read(j.at("macro_pixel_core"), "fraction", s.core_fraction);
    read(j.at("macro_pixel_core"), "magnification", s.core_magnification);
    read(j, "inside_fov", s.in_fov.count);
    s.in_fov.min_psnr_db = optional_number(j, "min_psnr_in_fov_db");
    s.in_fov.mean_psnr_db = optional_number(j, "mean_psnr_in_fov_db");
    s.in_fov.min_psnr_fitted_db = optional_number(j, "min_psnr_fitted_in_fov_db");
    s.in_fov.mean_psnr_fitted_db = optional_number(j, "mean_psnr_fitted_in_fov_db");
    s.in_fov.min_psnr_cell_db = optional_number(j, "min_psnr_cell_in_fov_db");
    read(j, "crosstalk_free", s.crosstalk_free.count);
    s.crosstalk_free.min_psnr_db = optional_number(j, "min_psnr_crosstalk_free_db");
    s.crosstalk_free.mean_psnr_db = optional_number(j, "mean_psnr_crosstalk_free_db");
    s.crosstalk_free.min_psnr_fitted_db = optional_number(j, "min_psnr_fitted_crosstalk_free_db");
    s.crosstalk_free.mean_psnr_fitted_db = optional_number(j, "mean_psnr_fitted_crosstalk_free_db");
    s.crosstalk_free.min_psnr_cell_db = optional_number(j, "min_psnr_cell_crosstalk_free_db");
    read(j, "accuracy_directions", s.accuracy_directions);
    read(j, "accuracy", s.accuracy);
}

void to_json(json& j, const ToleranceCurveRecord& c) {
    json sweep = json::array(), refinement = json::array();
    for (const auto& p : c.sweep)
        sweep.push_back({{"error", p.error}, {"psnr_db", p.psnr_db}, {"shift_lenslets", number_or_null(p.shift_lenslets)}});
    for (const auto& p : c.refinement) refinement.push_back({{"error", p.error}, {"psnr_db", p.psnr_db}});
    j = {{"kind", c.kind},
         {"unit", c.unit},
         {"max", c.max},
         {"tolerance", number_or_null(c.tolerance)},
         {"within_sweep", c.tolerance.has_value()},
         {"sweep", sweep},
         {"refinement", refinement},
         {"chart", c.chart}};
}

void from_json(const json& j, ToleranceCurveRecord& c) {
    read(j, "kind", c.kind);
    read(j, "unit", c.unit);
    read(j, "max", c.max);
    c.tolerance = optional_number(j, "tolerance");
    c.sweep.clear();
    c.refinement.clear();
    for (const json& p : j.at("sweep"))
        c.sweep.push_back({p.at("error").get<double>(), p.at("psnr_db").get<double>(), optional_number(p, "shift_lenslets")});
    for (const json& p : j.at("refinement"))
        c.refinement.push_back({p.at("error").get<double>(), p.at("psnr_db").get<double>(), std::nullopt});
    read(j, "chart", c.chart);
}

void to_json(json& j, const ToleranceSummary& s) {
    j = {{"design", s.design},         {"threshold_db", s.threshold_db}, {"model", s.model},
         {"lights", s.lights},         {"nominal_peak", s.nominal_peak}, {"summary", s.summary},
         {"curves", s.curves}};
}

void from_json(const json& j, ToleranceSummary& s) {
    read(j, "design", s.design);
    read(j, "threshold_db", s.threshold_db);
    read(j, "model", s.model);
    read(j, "lights", s.lights);
    read(j, "nominal_peak", s.nominal_peak);
    read(j, "summary", s.summary);
    read(j, "curves", s.curves);
}

void to_json(json& j, const VerdictReport& v) {
    json tolerances = nullptr;
    if (v.tolerances)
        tolerances = {{"shift_mm", number_or_null(v.tolerances->shift_mm)},
                      {"rotation_deg", number_or_null(v.tolerances->rotation_deg)},
                      {"pitch_error_ppm", number_or_null(v.tolerances->pitch_error_ppm)},
                      {"spacer_mm", number_or_null(v.tolerances->spacer_mm)},
                      {"at_least", v.tolerances->at_least}};
    j = {{"design", v.design},
         {"call", v.call},
         {"reason", v.reason},
         {"line", v.line},
         {"on_field", {{"call", v.field_call}, {"line", v.field_line}}},
         {"on_design", {{"call", v.design_call}, {"line", v.design_line}}},
         {"psnr_mean_in_fov_db", number_or_null(v.psnr_mean_in_fov_db)},
         {"psnr_min_in_fov_db", number_or_null(v.psnr_min_in_fov_db)},
         {"psnr_mean_crosstalk_free_db", number_or_null(v.psnr_mean_crosstalk_free_db)},
         {"directions_in_fov", v.directions_in_fov},
         {"directions_crosstalk_free", v.directions_crosstalk_free},
         {"field_of_view_deg", number_or_null(v.field_of_view_deg)},
         {"crosstalk_free_cone_deg", number_or_null(v.crosstalk_free_cone_deg)},
         {"tolerances", tolerances},
         {"warnings", v.warnings}};
}

void from_json(const json& j, VerdictReport& v) {
    read(j, "design", v.design);
    read(j, "call", v.call);
    read(j, "reason", v.reason);
    read(j, "line", v.line);
    read(j.at("on_field"), "call", v.field_call);
    read(j.at("on_field"), "line", v.field_line);
    read(j.at("on_design"), "call", v.design_call);
    read(j.at("on_design"), "line", v.design_line);
    v.psnr_mean_in_fov_db = optional_number(j, "psnr_mean_in_fov_db");
    v.psnr_min_in_fov_db = optional_number(j, "psnr_min_in_fov_db");
    v.psnr_mean_crosstalk_free_db = optional_number(j, "psnr_mean_crosstalk_free_db");
    read(j, "directions_in_fov", v.directions_in_fov);
    read(j, "directions_crosstalk_free", v.directions_crosstalk_free);
    v.field_of_view_deg = optional_number(j, "field_of_view_deg");
    v.crosstalk_free_cone_deg = optional_number(j, "crosstalk_free_cone_deg");
    v.tolerances.reset();
    if (const json& t = j.at("tolerances"); !t.is_null()) {
        VerdictReport::Tolerances tolerances;
        tolerances.shift_mm = optional_number(t, "shift_mm");
        tolerances.rotation_deg = optional_number(t, "rotation_deg");
        tolerances.pitch_error_ppm = optional_number(t, "pitch_error_ppm");
        tolerances.spacer_mm = optional_number(t, "spacer_mm");
        read(t, "at_least", tolerances.at_least);
        v.tolerances = tolerances;
    }
    read(j, "warnings", v.warnings);
}

void to_json(json& j, const RegistrationSummary& r) {
    j = {{"design", r.design},
         {"photographs", r.photographs},
         {"light", r.light},
         {"shift_mm", r.shift_mm},
         {"sigma_shift_mm", r.sigma_shift_mm},
         {"rotation_deg", r.rotation_deg},
         {"sigma_rotation_deg", r.sigma_rotation_deg},
         {"scale_error", r.scale_error},
         {"sigma_scale_error", r.sigma_scale_error},
         {"tolerance_shift_mm", number_or_null(r.tolerance_shift_mm)},
         {"tolerance_rotation_deg", number_or_null(r.tolerance_rotation_deg)},
         {"inside", r.inside ? json(*r.inside) : json()}};
}

void from_json(const json& j, RegistrationSummary& r) {
    read(j, "design", r.design);
    read(j, "photographs", r.photographs);
    read(j, "light", r.light);
    read(j, "shift_mm", r.shift_mm);
    read(j, "sigma_shift_mm", r.sigma_shift_mm);
    read(j, "rotation_deg", r.rotation_deg);
    read(j, "sigma_rotation_deg", r.sigma_rotation_deg);
    read(j, "scale_error", r.scale_error);
    read(j, "sigma_scale_error", r.sigma_scale_error);
    r.tolerance_shift_mm = optional_number(j, "tolerance_shift_mm");
    r.tolerance_rotation_deg = optional_number(j, "tolerance_rotation_deg");
    const json& inside = j.at("inside");
    r.inside = inside.is_null() ? std::nullopt : std::optional<bool>(inside.get<bool>());
}

template <class Summary>
std::string summary_text(const Summary& value) {
    return json(value).dump(2) + "\n";
}

template <class Summary>
void write_summary(const std::filesystem::path& file, const Summary& value) {
    write_text_file(file, summary_text(value));
}

template <class Summary>
Summary read_summary(const std::filesystem::path& file) {
    std::ifstream in(file);
    if (!in) throw IoError(SourceLocation{file.string()}, "cannot open");
    try {
        return json::parse(in).get<Summary>();
    } catch (const json::exception& error) {
        throw InputError(SourceLocation{file.string()}, std::string("not what rfd writes there: ") + error.what());
    }
}

template void write_summary(const std::filesystem::path&, const CompareSummary&);
template void write_summary(const std::filesystem::path&, const ToleranceSummary&);
template void write_summary(const std::filesystem::path&, const VerdictReport&);
template CompareSummary read_summary(const std::filesystem::path&);
template ToleranceSummary read_summary(const std::filesystem::path&);
template VerdictReport read_summary(const std::filesystem::path&);
template void write_summary(const std::filesystem::path&, const RegistrationSummary&);
template RegistrationSummary read_summary(const std::filesystem::path&);
template std::string summary_text(const RegistrationSummary&);
template std::string summary_text(const CompareSummary&);
template std::string summary_text(const ToleranceSummary&);
template std::string summary_text(const VerdictReport&);

}  // namespace rfd::predict
