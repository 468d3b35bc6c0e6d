#pragma once
// Line charts through gnuplot (a program we run, found at configure time or on PATH):
// the data go to CSV, the chart to a readable .gp script beside it, and gnuplot renders
// SVG and PNG. Without gnuplot, the CSV and the script are still written and a ToolError
// says what is missing.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

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
    bool log_y = false;
};

/// Writes `stem`.csv (one x column per series), `stem`.gp, and renders `stem`.svg and
/// `stem`.png. All files are written atomically. Throws ToolError when gnuplot is missing
/// or fails (after the CSV and script are in place).
void write_line_chart(const LineChart& chart, const std::filesystem::path& stem);

/// Path of the gnuplot binary, or nullopt.
std::optional<std::filesystem::path> find_gnuplot();

}  // namespace rfd
