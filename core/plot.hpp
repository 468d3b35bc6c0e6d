#pragma once
// Line charts through gnuplot (a program we run, found at configure time or on PATH):
// the data go to CSV, the chart to a readable .gp script beside it, and gnuplot renders
// SVG and PNG. Without gnuplot, the CSV and the script are still written and a ToolError
// says what is missing.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace rfd {

struct PlotSeries {
    std::string title;
    std::vector<double> x, y;  ///< NaN y values leave a gap
    bool right_axis = false;   ///< plot against the second y axis
};

struct LineChart {
    std::string title;
    std::string x_label, y_label, y2_label;
    std::vector<PlotSeries> series;
    std::vector<std::pair<double, std::string>> vertical_markers;  ///< x position, label
    bool log_x = false;  ///< logarithmic x axis (non-positive x values are not drawn)
    bool log_y = false;
    std::string key_position = "top left";  ///< gnuplot's words: "top right", "bottom left"...
};

/// Writes `stem`.csv (one x column per series), `stem`.gp, and renders `stem`.svg and
/// `stem`.png. All files are written atomically. Throws ToolError when gnuplot is missing
/// or fails (after the CSV and script are in place).
void write_line_chart(const LineChart& chart, const std::filesystem::path& stem);

/// Values over the upper hemisphere of light directions, as in thesis figure 5.4: a polar
/// plot with theta (degrees from the zenith) as the radius and phi as the angle (0 to the
/// right, counter-clockwise, field frame of core/sphere.hpp), one dot per direction coloured
/// by its value.
/// Example: write_polar_map({"error per direction", field.directions, errors, "squared error"}, "out/error");
struct PolarMap {
    std::string title;
    std::vector<Eigen::Vector3d> directions;  ///< unit, field frame
    std::vector<double> values;               ///< one per direction; NaN draws no dot
    std::string colour_label;
    bool log_colour = false;                  ///< logarithmic colour scale (positive values)
};

/// Writes `stem`.csv (theta_deg, phi_deg, x, y, value), `stem`.gp, and renders `stem`.svg and
/// `stem`.png, like write_line_chart (atomic writes, ToolError without gnuplot).
void write_polar_map(const PolarMap& map, const std::filesystem::path& stem);

/// Path of the gnuplot binary, or nullopt.
std::optional<std::filesystem::path> find_gnuplot();

}  // namespace rfd
