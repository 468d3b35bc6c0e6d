#include "optics/accuracy_chart.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/json.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/plot.hpp"
#include "core/text.hpp"
#include "core/units.hpp"

namespace rfd::optics {
Chart accuracy_chart(const DesignOptics& optics, double phi, const std::string& name,
                     double max_angle_deg, int steps) {
    Chart chart;
    chart.direction = name;
    const Eigen::Vector2d along(std::cos(phi), std::sin(phi));
    const Eigen::Vector2d dot = optics.dot_mm();
    const double pixel = std::hypot(along.x() * dot.x(), along.y() * dot.y());
    const CellIndex cell = optics.centre_cell();
    for (int k = 0; k <= steps; ++k) {
        ChartRow row;
        row.angle_deg = max_angle_deg * k / steps;
        const auto d = incident_direction(degrees_to_radians(row.angle_deg), phi);
        const auto paraxial = optics.land(d, cell, Model::Paraxial);
        const auto exact = optics.land(d, cell, Model::Exact);
        row.exact_status = exact.status;
        // Both models must reach the encoding plane (landing there under a neighbouring
        // lenslet counts: that is where wrap-over shows); a ray stopped earlier has no
        // position on it to compare.
        const auto reached = [&](const DesignOptics::Landing& l) {
            return l.surface == static_cast<int>(optics.encoding_surface()) &&
                   (l.status == RayStatus::Ok || l.status == RayStatus::CrossedCell);
        };
        const bool arrived = reached(exact) && reached(paraxial);
        row.paraxial_mm = reached(paraxial) ? paraxial.offset.dot(along) : std::nan("");
        row.exact_mm = arrived ? exact.offset.dot(along) : std::nan("");
        row.error_um = arrived ? 1000.0 * (row.exact_mm - row.paraxial_mm) : std::nan("");
        row.error_pixels = arrived ? (row.exact_mm - row.paraxial_mm) / pixel : std::nan("");
        if (!chart.half_pixel_angle_deg && arrived && std::abs(row.error_pixels) > 0.5)
            chart.half_pixel_angle_deg = row.angle_deg;
        chart.rows.push_back(row);
    }
    return chart;
}

double measure_rays_per_second(const DesignOptics& optics, Model model, std::size_t rays,
                               double max_angle_deg) {
    const SequentialSystem& system = optics.system();
    const Eigen::Vector2d half = optics.lattice().half_extent();
    const double z0 = system.surfaces.front().z - 2.0;
    const double max_slope = std::tan(degrees_to_radians(max_angle_deg));
    std::mt19937_64 random(12345);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    const std::size_t last = optics.encoding_surface();
    using Clock = std::chrono::steady_clock;
    if (model == Model::Exact) {
        RayBatch batch;
        batch.resize(rays);
        for (std::size_t k = 0; k < rays; ++k) {
            const Eigen::Vector3d d =
                Eigen::Vector3d(max_slope * unit(random), max_slope * unit(random), 1.0).normalized();
            batch.set(k, Ray{Eigen::Vector3d(half.x() * unit(random), half.y() * unit(random), z0), d});
        }
        const auto start = Clock::now();
        trace_batch(system, batch, 0, last);
        const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
        return static_cast<double>(rays) / std::max(seconds, 1e-9);
    }
    ParaxialBatch batch;
    batch.resize(rays);
    for (std::size_t k = 0; k < rays; ++k) {
        batch.x[k] = half.x() * unit(random);
        batch.y[k] = half.y() * unit(random);
        batch.tx[k] = max_slope * unit(random);
        batch.ty[k] = max_slope * unit(random);
    }
    const auto start = Clock::now();
    trace_paraxial_batch(system, batch, z0, 0, last);
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    return static_cast<double>(rays) / std::max(seconds, 1e-9);
}

ModelAccuracy chart_model_accuracy(const DesignOptics& optics, const ModelAccuracySettings& settings) {
    ModelAccuracy run;
    run.design = optics.design().name;
    run.sweeps = sweep_directions(optics.lattice());
    // The chart reaches a quarter past the first wrap-over; where no direction wraps
    // over, to 75 deg and the rays/s are measured at 48 deg.
    constexpr double kNoWrapOverDeg = 60.0;
    double wrap = kNoWrapOverDeg;
    bool wraps = false;
    for (const auto& sweep : run.sweeps) {
        run.wrap_over_deg.push_back(wrap_over_angle(optics, sweep.phi, Model::Exact));
        if (const auto angle = run.wrap_over_deg.back()) {
            wrap = wraps ? std::min(wrap, *angle) : *angle;
            wraps = true;
        }
    }
    run.max_angle_deg =
        settings.max_angle_deg > 0 ? settings.max_angle_deg : std::min(kWrapOverSearchLimitDeg, 1.25 * wrap);
    // Rays per second are a measurement of this machine, the only part of the output
    // that changes from run to run.
    if (settings.timing_rays) {
        run.paraxial_rays_per_second = measure_rays_per_second(optics, Model::Paraxial, *settings.timing_rays, 0.8 * wrap);
        run.exact_rays_per_second = measure_rays_per_second(optics, Model::Exact, *settings.timing_rays, 0.8 * wrap);
    }
    for (const auto& sweep : run.sweeps)
        run.charts.push_back(accuracy_chart(optics, sweep.phi, sweep.name, run.max_angle_deg, settings.steps));
    return run;
}

nlohmann::json write_model_accuracy(const std::filesystem::path& folder, const ModelAccuracy& run) {
    ensure_directory(folder);
    const bool timed = run.paraxial_rays_per_second && run.exact_rays_per_second;
    std::optional<double> ratio;
    if (timed) ratio = *run.paraxial_rays_per_second / *run.exact_rays_per_second;
    nlohmann::json summary = {{"design", run.design},
                              {"paraxial_rays_per_second", json_or_null(run.paraxial_rays_per_second)},
                              {"exact_rays_per_second", json_or_null(run.exact_rays_per_second)},
                              {"exact_over_paraxial_time", json_or_null(ratio)},
                              {"sweeps", nlohmann::json::array()}};
    for (std::size_t k = 0; k < run.sweeps.size(); ++k) {
        const SweepDirection& sweep = run.sweeps[k];
        const Chart& chart = run.charts[k];
        LineChart plot;
        char title[400];
        if (!timed)
            std::snprintf(title, sizeof title, "%s\nparaxial against exact along the %s direction", run.design.c_str(),
                          sweep.name.c_str());
        else
            std::snprintf(title, sizeof title,
                          "%s\nparaxial against exact along the %s direction; paraxial %.3g rays/s, exact %.3g rays/s",
                          run.design.c_str(), sweep.name.c_str(), *run.paraxial_rays_per_second,
                          *run.exact_rays_per_second);
        plot.title = title;
        plot.x_label = "incident angle (degrees)";
        plot.y_label = "paraxial error on the encoding plane (print pixels)";
        plot.y2_label = "error (micrometres)";
        PlotSeries pixels{"error in print pixels", {}, {}, false};
        PlotSeries microns{"error in micrometres", {}, {}, true};
        for (const auto& row : chart.rows) {
            pixels.x.push_back(row.angle_deg), pixels.y.push_back(row.error_pixels);
            microns.x.push_back(row.angle_deg), microns.y.push_back(row.error_um);
        }
        plot.series = {pixels, microns};
        if (chart.half_pixel_angle_deg) plot.vertical_markers.emplace_back(*chart.half_pixel_angle_deg, "error > 1/2 pixel");
        if (run.wrap_over_deg[k]) plot.vertical_markers.emplace_back(*run.wrap_over_deg[k], "wrap-over");
        write_line_chart(plot, folder / ("paraxial_error_" + sweep.file));
        summary["sweeps"].push_back({{"direction", sweep.name},
                                     {"half_pixel_error_angle_deg", json_or_null(chart.half_pixel_angle_deg)},
                                     {"files", "paraxial_error_" + sweep.file + ".{csv,gp,svg,png}"}});
    }
    write_text_file(folder / "chart.json", summary.dump(2) + "\n");
    return summary;
}

std::string model_accuracy_text(const ModelAccuracy& run, const std::string& folder) {
    std::string text = run.design + "\n";
    if (run.paraxial_rays_per_second && run.exact_rays_per_second) {
        text += format_text("  paraxial: %.3g rays/s, exact: %.3g rays/s (exact takes %.1fx as long)\n",
                      *run.paraxial_rays_per_second, *run.exact_rays_per_second,
                      *run.paraxial_rays_per_second / *run.exact_rays_per_second);
    }
    for (std::size_t k = 0; k < run.sweeps.size(); ++k) {
        const std::optional<double>& angle = run.charts[k].half_pixel_angle_deg;
        if (!angle)
            text += format_text("  %s: paraxial error stays below half a print pixel up to %.1f deg\n",
                          run.sweeps[k].name.c_str(), run.max_angle_deg);
        else
            text += format_text("  %s: paraxial error exceeds half a print pixel from %.2f deg\n",
                                run.sweeps[k].name.c_str(), *angle);
    }
    return text + "  written to " + folder + "\n";
}

}  // namespace rfd::optics
