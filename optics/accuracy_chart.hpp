#pragma once
// How far the paraxial model is from the exact one (`rfd optics chart`): per incident angle
// along each sweep direction, the landing error on the encoding plane in print dots and
// micrometres, and each model's rays per second; the chart files and their summary.
//
// Example:
//   const ModelAccuracy run = chart_model_accuracy(optics, {.steps = 120});
//   write_model_accuracy("chart", run);   // paraxial_error_x.{csv,gp,svg,png}, chart.json

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "optics/analysis.hpp"
#include "optics/design_optics.hpp"
#include "optics/model.hpp"

namespace rfd::optics {

/// One line of the speed-versus-accuracy chart: paraxial against exact landing position.
struct ChartRow {
    double angle_deg = 0;
    double paraxial_mm = 0, exact_mm = 0;  ///< landing offset along the sweep direction
    double error_um = 0;
    double error_pixels = 0;               ///< in print dots along the sweep direction
    RayStatus exact_status = RayStatus::Ok;
};
struct Chart {
    std::string direction;  ///< "x" or "y" (the flat or corner direction for hex cells)
    std::vector<ChartRow> rows;
    std::optional<double> half_pixel_angle_deg;  ///< where |error| first exceeds 0.5 px
};
Chart accuracy_chart(const DesignOptics& optics, double phi_rad, const std::string& name,
                     double max_angle_deg, int steps);

/// Rays per second each model traces from the entrance to the encoding plane, measured
/// on `rays` rays spread over the array within +-`max_angle_deg`, with the batch tracers
/// (all cores). A wall-clock measurement: it varies from machine to machine and run to run.
double measure_rays_per_second(const DesignOptics& optics, Model model, std::size_t rays,
                               double max_angle_deg);

/// What `rfd optics chart` measures.
struct ModelAccuracySettings {
    int steps = 120;                    ///< angles per sweep
    double max_angle_deg = 0.0;         ///< 0: a quarter past the first exact wrap-over
    std::optional<std::size_t> timing_rays = 400000;  ///< nullopt: no rays/s (a byte-identical report)
};
struct ModelAccuracy {
    std::string design;                 ///< the design's name
    double max_angle_deg = 0.0;         ///< as charted
    std::optional<double> paraxial_rays_per_second, exact_rays_per_second;
    std::vector<SweepDirection> sweeps;
    std::vector<Chart> charts;          ///< one per sweep
    std::vector<std::optional<double>> wrap_over_deg;  ///< per sweep, exact model
};
ModelAccuracy chart_model_accuracy(const DesignOptics& optics, const ModelAccuracySettings& settings);

/// FOLDER/paraxial_error_FILE.{csv,gp,svg,png} per sweep and chart.json (the summary,
/// returned too).
nlohmann::json write_model_accuracy(const std::filesystem::path& folder, const ModelAccuracy& run);
/// What the command prints: the rates and where each sweep's error passes half a dot.
std::string model_accuracy_text(const ModelAccuracy& run, const std::string& folder);

}  // namespace rfd::optics
