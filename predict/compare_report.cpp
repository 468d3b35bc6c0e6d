#include "predict/compare_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "core/csv.hpp"
#include "core/files.hpp"
#include "core/image_io.hpp"
#include "core/plot.hpp"
#include "core/progress.hpp"
#include "core/text.hpp"
#include "core/units.hpp"

namespace rfd::predict {
namespace {

// light_00, light_01, ...: a direction's files in the report.
std::string image_stem(std::size_t k) {
    char stem[32];
    std::snprintf(stem, sizeof stem, "light_%02zu", k);
    return stem;
}

// A PSNR cell of a table: 4 decimals, empty for none.
std::string optional_text(const std::optional<double>& value) {
    return value ? format_fixed(*value, 4) : std::string();
}

// directions.csv: summary.json's directions as a table (no times: byte-identical reruns).
CsvTable directions_csv(const CompareSummary& summary) {
    CsvTable table({"index", "field_theta_deg", "field_phi_deg", "display_angle_deg", "inside_fov", "crosstalk_free",
                    "efficiency", "peak", "mse", "psnr_db", "psnr_own_peak_db", "fitted_gain", "psnr_fitted_db",
                    "psnr_cell_db"});
    for (std::size_t k = 0; k < summary.directions.size(); ++k) {
        const CompareDirection& d = summary.directions[k];
        table.add_row({std::to_string(k), format_fixed(d.field_theta_deg, 4), format_fixed(d.field_phi_deg, 4),
                       format_fixed(d.display_angle_deg, 4), csv_flag(d.inside_fov), csv_flag(d.crosstalk_free),
                       format_number(d.efficiency), format_number(d.peak), format_number(d.mse),
                       optional_text(d.psnr_db), optional_text(d.psnr_own_peak_db), format_number(d.fitted_gain),
                       optional_text(d.psnr_fitted_db), optional_text(d.psnr_cell_db)});
    }
    return table;
}

// PSNR against the light's angle from the display's axis, inside and outside the FOV.
LineChart psnr_chart(const CompareSummary& summary, bool cores) {
    std::vector<const CompareDirection*> order;
    for (const auto& d : summary.directions) order.push_back(&d);
    std::stable_sort(order.begin(), order.end(),
                     [](const auto* a, const auto* b) { return a->display_angle_deg < b->display_angle_deg; });
    LineChart chart;
    chart.title = "Predicted output against software relighting: " + summary.design;
    chart.x_label = "light's angle to the display's axis (degrees)";
    chart.y_label = "PSNR against the field's brightest (dB)";
    chart.key_position = "bottom left";
    PlotSeries clean{"crosstalk-free", {}, {}}, crosstalk{"inside the FOV, with crosstalk", {}, {}},
        outside{"outside the FOV (wrap-over)", {}, {}}, cells{"over whole cells", {}, {}};
    const auto value = [](const std::optional<double>& v) { return v.value_or(std::nan("")); };
    for (const CompareDirection* d : order) {
        PlotSeries& zone = d->crosstalk_free ? clean : d->inside_fov ? crosstalk : outside;
        zone.x.push_back(d->display_angle_deg);
        zone.y.push_back(value(d->psnr_db));
        if (cores) {
            cells.x.push_back(d->display_angle_deg);
            cells.y.push_back(value(d->psnr_cell_db));
        }
    }
    for (PlotSeries* series : {&clean, &crosstalk, &outside, &cells})
        if (!series->x.empty()) chart.series.push_back(*series);
    return chart;
}

std::optional<double> finite(double value) {
    return std::isfinite(value) ? std::optional<double>(value) : std::nullopt;
}

// One accuracy point as summary.json records it; `angles` are its directions' angles.
AccuracyRecord accuracy_record(const AccuracyPoint& p, const std::vector<double>& angles) {
    AccuracyRecord record{p.label, p.rays_per_side, static_cast<long long>(p.rays), p.seconds, p.mse,
                                   finite(p.psnr_db), finite(p.worst_psnr_db), finite(p.fitted_psnr_db), {}};
    for (std::size_t k = 0; k < p.psnr_per_direction_db.size() && k < angles.size(); ++k)
        record.per_direction.push_back(
            {angles[k], finite(p.psnr_per_direction_db[k]), finite(p.fitted_psnr_per_direction_db[k])});
    return record;
}

CsvTable accuracy_csv(const std::vector<AccuracyPoint>& points) {
    CsvTable table({"model", "rays_per_side", "rays", "seconds", "mse", "psnr_db", "worst_psnr_db", "fitted_psnr_db"});
    for (const auto& p : points)
        table.add_row({p.label, std::to_string(p.rays_per_side), std::to_string(p.rays), format_fixed(p.seconds, 5),
                       format_number(p.mse), format_fixed(p.psnr_db, 4), format_fixed(p.worst_psnr_db, 4),
                       format_fixed(p.fitted_psnr_db, 4)});
    return table;
}

LineChart accuracy_chart(const std::string& design, const std::vector<AccuracyModel>& models,
                         const std::vector<AccuracyPoint>& points, std::size_t directions, int reference_rays) {
    LineChart speed;
    speed.title = "Simulator speed against accuracy: " + design;
    speed.x_label = "simulation time over " + std::to_string(directions) + " directions in the field of view (s)";
    speed.y_label = "PSNR per lenslet against exact, " + std::to_string(reference_rays) + " rays per side (dB)";
    speed.key_position = "bottom right";
    for (const auto& model : models) {
        PlotSeries raw{model.label, {}, {}}, fitted{model.label + ", scale fitted", {}, {}};
        for (const auto& p : points)
            if (p.label == model.label) {
                raw.x.push_back(p.seconds);
                raw.y.push_back(std::isfinite(p.psnr_db) ? p.psnr_db : std::nan(""));
                fitted.x.push_back(p.seconds);
                fitted.y.push_back(std::isfinite(p.fitted_psnr_db) ? p.fitted_psnr_db : std::nan(""));
            }
        speed.series.push_back(raw);
        speed.series.push_back(fitted);
    }
    return speed;
}

}  // namespace

ComparisonRun run_comparison(const optics::DisplaySimulator& simulator, const print::PrintedTransparency& pattern,
                             const DisplayComparison& comparison, const ComparisonSettings& settings) {
    std::vector<Eigen::Vector3d> directions = comparison.sweep(settings.sweep);
    directions.insert(directions.end(), settings.lights.begin(), settings.lights.end());
    ComparisonRun run;
    {
        Progress progress("comparing", directions.size());
        for (const Eigen::Vector3d& v : directions) {
            run.results.push_back(comparison.compare(v, settings.options));
            progress.advance();
        }
    }
    std::vector<std::string> images;
    for (std::size_t k = 0; k < run.results.size(); ++k) images.push_back(image_stem(k) + ".png");
    run.summary = summarise_comparison(run.results, images);
    const patterns::Encoder& encoder = comparison.encoder();
    run.summary.model = std::string(optics::to_string(settings.options.model));
    run.summary.rays_per_side = settings.options.rays_per_side;
    run.summary.lenslets = {encoder.lattice().count_x(), encoder.lattice().count_y()};
    run.summary.display_range_deg = radians_to_degrees(encoder.display_range().max_angle_rad);
    if (settings.accuracy_models.empty()) return run;

    // Inside the field of view, where a model's error matters (all when none is).
    std::vector<Eigen::Vector3d> display_directions;
    for (const auto& r : run.results)
        if (r.inside_field_of_view) display_directions.push_back(r.display_direction);
    if (display_directions.empty())
        for (const auto& r : run.results) display_directions.push_back(r.display_direction);
    run.summary.accuracy_directions = display_directions.size();
    run.accuracy = accuracy_sweep(simulator, pattern, display_directions, settings.accuracy_models,
                                  settings.accuracy_rays, settings.reference_rays, settings.options);
    std::vector<double> angles;
    for (const auto& r : run.results)
        if (r.inside_field_of_view || run.summary.accuracy_directions == run.results.size())
            angles.push_back(r.display_angle_deg);
    for (const auto& p : run.accuracy) run.summary.accuracy.push_back(accuracy_record(p, angles));
    return run;
}

void write_comparison_report(const std::filesystem::path& folder, const ComparisonRun& run,
                             const ComparisonSettings& settings, const ComparisonPictures& pictures) {
    ensure_directory(folder);
    const int count_x = run.summary.lenslets[0];
    const int view_pixels =
        pictures.pixels_per_lenslet > 0 ? pictures.pixels_per_lenslet : std::max(1, 240 / std::max(count_x, 1));
    std::vector<Image> panels;  // prediction | reference | error, per direction
    for (std::size_t k = 0; k < run.results.size(); ++k) {
        const DirectionComparison& r = run.results[k];
        const std::string stem = image_stem(k);
        write_image(folder / (stem + "_prediction.exr"), r.prediction);
        write_image(folder / (stem + "_reference.exr"), r.reference);
        write_image(folder / (stem + "_error.exr"), r.comparison.error);
        panels.push_back(side_by_side(r, view_pixels, pictures.error_gain));
        write_image(folder / (stem + ".png"), panels.back());
    }
    directions_csv(run.summary).write(folder / "directions.csv");
    // Every direction's panels on one page, in the order of directions.csv.
    write_image(folder / "contact_sheet.png", tiled(panels, 3, 4, 1.0f));
    if (!run.accuracy.empty()) accuracy_csv(run.accuracy).write(folder / "accuracy_points.csv");
    write_summary(folder / "summary.json", run.summary);
    // Charts last: a missing gnuplot still leaves every number on disk.
    write_line_chart(psnr_chart(run.summary, run.summary.core_fraction < 1.0), folder / "psnr");
    if (!run.accuracy.empty())
        write_line_chart(accuracy_chart(run.summary.design, settings.accuracy_models, run.accuracy,
                                        run.summary.accuracy_directions, settings.reference_rays),
                         folder / "accuracy");
}

std::string comparison_text(const std::string& out, const ComparisonRun& run, int reference_rays) {
    const CompareSummary& s = run.summary;
    const std::vector<AccuracyPoint>& points = run.accuracy;
    std::string text;
    const auto db = [](const std::optional<double>& v) { return v ? format_fixed(*v, 2) : std::string("-"); };
    text += format_text("%s: '%s' predicted against the relit field at %d x %d lenslets (model %s, %d rays per side)\n",
                out.c_str(), s.design.c_str(), s.lenslets[0], s.lenslets[1], s.model.c_str(), s.rays_per_side);
    if (s.core_fraction < 1.0)
        text += format_text("  macro-pixels %.3fx their cells: PSNR over each cell's core (%.0f %% of its width), "
                    "\"cell\" over whole cells\n",
                    s.core_magnification, 100.0 * s.core_fraction);
    text += format_text("  PSNR against the field's brightest value, %s\n", format_number(s.field_peak).c_str());
    text += format_text("  %-5s %8s %8s %8s %9s %8s %9s %9s %9s %9s\n", "light", "theta", "phi", "angle", "fov", "eta",
                "PSNR dB", "own peak", "fitted dB", "cell dB");
    for (std::size_t k = 0; k < s.directions.size(); ++k) {
        const CompareDirection& d = s.directions[k];
        text += format_text("  %-5zu %8.2f %8.2f %8.2f %9s %8.4f %9s %9s %9s %9s\n", k, d.field_theta_deg, d.field_phi_deg,
                    d.display_angle_deg, d.crosstalk_free ? "in" : d.inside_fov ? "crosstalk" : "out", d.efficiency,
                    db(d.psnr_db).c_str(), db(d.psnr_own_peak_db).c_str(), db(d.psnr_fitted_db).c_str(),
                    db(d.psnr_cell_db).c_str());
    }
    const std::size_t count = s.directions.size();
    if (s.crosstalk_free.count)
        text += format_text("  crosstalk-free (%d of %zu): PSNR min %s dB, mean %s dB (cells: min %s dB)\n",
                    s.crosstalk_free.count, count, db(s.crosstalk_free.min_psnr_db).c_str(),
                    db(s.crosstalk_free.mean_psnr_db).c_str(), db(s.crosstalk_free.min_psnr_cell_db).c_str());
    if (s.in_fov.count)
        text += format_text("  inside the field of view (%d of %zu): PSNR min %s dB, mean %s dB (fitted gain: min %s, "
                    "mean %s; cells: min %s dB)\n",
                    s.in_fov.count, count, db(s.in_fov.min_psnr_db).c_str(), db(s.in_fov.mean_psnr_db).c_str(),
                    db(s.in_fov.min_psnr_fitted_db).c_str(), db(s.in_fov.mean_psnr_fitted_db).c_str(),
                    db(s.in_fov.min_psnr_cell_db).c_str());
    else
        text += format_text("  no direction inside the field of view\n");
    if (!points.empty()) {
        text += format_text("  speed against accuracy over %zu directions (reference: exact, %d rays per side):\n",
                    s.accuracy_directions, reference_rays);
        text += format_text("  %-16s %6s %10s %10s %9s %9s %10s\n", "model", "rays", "traced", "seconds", "PSNR dB", "worst dB",
                    "fitted dB");
        for (const auto& p : points)
            text += format_text("  %-16s %6d %10zu %10.4f %9.2f %9.2f %10.2f\n", p.label.c_str(), p.rays_per_side, p.rays,
                        p.seconds, p.psnr_db, p.worst_psnr_db, p.fitted_psnr_db);
    }
    return text;
}

}  // namespace rfd::predict
