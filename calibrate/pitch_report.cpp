#include "calibrate/pitch_report.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/plot.hpp"
#include "core/text.hpp"
#include "print/moire.hpp"

namespace rfd::calibrate {
namespace {

// The array part's name: the lattice print::moire_lattice calibrates.
std::string array_part_name(const optics::Design& design) {
    const auto is_array = [](const optics::Plane& plane) {
        return plane.part && std::holds_alternative<optics::LensletArrayPart>(*plane.part);
    };
    if (is_array(design.pattern_plane())) return design.pattern_plane().part_name;
    for (const optics::Plane& plane : design.planes)
        if (is_array(plane)) return plane.part_name;
    throw InputError(SourceLocation{design.file}, "design has no lenslet array to calibrate");
}

// The one pitch of a hexagonal lattice from both axes (rows lie pitch sqrt(3)/2 apart, so
// the row spacing's scale is the pitch's too), weighted by their variances.
std::pair<double, double> hexagonal_scale(const PitchCalibration& c) {
    const double wx = 1.0 / (c.sigma_scale_x * c.sigma_scale_x), wy = 1.0 / (c.sigma_scale_y * c.sigma_scale_y);
    return {(wx * c.scale_x + wy * c.scale_y) / (wx + wy), std::sqrt(1.0 / (wx + wy))};
}

}  // namespace

std::string pitch_text(const PitchCalibration& calibration, const std::vector<PitchReading>& readings) {
    std::string out;
    for (std::size_t k = 0; k < readings.size(); ++k) {
        const PitchReading& r = readings[k];
        // The axes' departure from square needs both bands in one photograph (a whole small
        // array is photographed on each band in turn).
        const double shear = calibration.shear_deg[k];
        const std::string square =
            std::isfinite(shear) ? format_text("axes %+.4f deg off square", shear)
                                 : std::string("the ") + (r.x.lenslets > 0 ? "x" : "rows") + " band only";
        out += format_text("%s: %.3f mm a pixel%s; rows turned %+.4f deg (+- %.4f) on the sheet, %s\n",
                           r.name.c_str(), r.mm_per_pixel, r.mirrored ? ", sheet seen from its back" : "",
                           calibration.rotation_deg[k], calibration.sigma_rotation_deg[k], square.c_str());
        for (const AxisFit* fit : {&r.x, &r.y})
            out += format_text("  %-4s bands: %d lenslets read in %d bands (%d outliers), line contrast %.2f, "
                               "residual %.2f %%\n",
                               fit->along_x ? "x" : "row", fit->lenslets, fit->bands, fit->outliers, fit->contrast,
                               100.0 * fit->rms);
        if (r.discs_drift())
            out += format_text("  the lenslet images' lattice is %.3f %% out of the shape the lines measure (the "
                               "reading discs drift across the images; the uncertainty includes it)\n",
                               100.0 * r.lattice_mismatch);
    }
    if (calibration.sheet_scale_x != 1.0 || calibration.sheet_scale_y != 1.0)
        out += format_text("sheet printed at %.5f x %.5f of its size (from --sheet-scale)\n", calibration.sheet_scale_x,
                           calibration.sheet_scale_y);
    out += format_text("pitch along a row: %.6f mm, design %.6f mm: %+.4f %% (+- %.4f %%)\n", calibration.pitch_x(),
                       calibration.design_pitch_x, 100.0 * (calibration.scale_x - 1.0),
                       100.0 * calibration.sigma_scale_x);
    out += format_text("row spacing:       %.6f mm, design %.6f mm: %+.4f %% (+- %.4f %%)\n", calibration.pitch_y(),
                       calibration.design_pitch_y, 100.0 * (calibration.scale_y - 1.0),
                       100.0 * calibration.sigma_scale_y);
    // Where the lenslets read few of the lines' phases (a small array at some turns) the scale
    // is still given, with its larger uncertainty, and how to read it finer.
    constexpr double kFineScale = 5e-5;
    const bool drifting =
        std::any_of(readings.begin(), readings.end(), [](const PitchReading& r) { return r.discs_drift(); });
    if (std::max(calibration.sigma_scale_x, calibration.sigma_scale_y) > kFineScale)
        out += drifting ? "uncertain beyond 0.005 %: photograph the sheet again with the sun behind the display, "
                          "within 20 deg of its axis, the display evenly lit, and give all the photographs\n"
                        : "uncertain beyond 0.005 %: turn the array a degree or two on the band (or lay it down "
                          "again), photograph it again and give all the photographs\n";
    return out;
}

std::string calibrated_design_text(const optics::Design& design, const PitchCalibration& calibration,
                                   const std::vector<PitchReading>& readings) {
    const std::string part = array_part_name(design);
    const bool hex = print::moire_lattice(design).kind() == optics::LatticeKind::Hexagonal;
    std::string pitch_line;
    if (hex) {
        const auto [scale, sigma] = hexagonal_scale(calibration);
        pitch_line = format_text("pitch_mm = %.6f   # measured by rfd calibrate pitch from %zu photograph(s): %+.4f %% "
                                 "(+- %.4f %%) against the design's %.6f mm",
                                 calibration.design_pitch_x * scale, readings.size(), 100.0 * (scale - 1.0),
                                 100.0 * sigma, calibration.design_pitch_x);
    } else {
        pitch_line = format_text("pitch_mm = [%.6f, %.6f]   # measured by rfd calibrate pitch from %zu photograph(s): "
                                 "%+.4f %%, %+.4f %% against the design's [%.6f, %.6f] mm",
                                 calibration.pitch_x(), calibration.pitch_y(), readings.size(),
                                 100.0 * (calibration.scale_x - 1.0), 100.0 * (calibration.scale_y - 1.0),
                                 calibration.design_pitch_x, calibration.design_pitch_y);
    }
    std::istringstream in(read_text_file(design.file));
    std::string out, line;
    bool inside = false, replaced = false;
    while (std::getline(in, line)) {
        const std::size_t first = line.find_first_not_of(" \t");
        const std::string trimmed = first == std::string::npos ? "" : line.substr(first);
        if (!trimmed.empty() && trimmed.front() == '[') inside = trimmed.starts_with("[parts." + part + "]");
        if (inside && !replaced && (trimmed.starts_with("pitch_mm") || trimmed.starts_with("lenses_per_cm2"))) {
            out += pitch_line + "\n";
            replaced = true;
            continue;
        }
        out += line + "\n";
    }
    if (!replaced)
        throw InputError(SourceLocation{design.file, 0, 0, "parts." + part},
                         "no pitch_mm or lenses_per_cm2 line to replace with the measured pitch");
    optics::parse_design(out, design.file);  // what is written must read back
    return out;
}

void write_pitch_report(const std::vector<PitchReading>& readings, const std::filesystem::path& folder) {
    ensure_directory(folder);
    CsvTable table({"photo", "page_x_mm", "page_y_mm", "band", "value", "phase", "fitted", "outlier"});
    for (const PitchReading& r : readings)
        for (const LensletReading& l : r.lenslets)
            table.add_row({r.name, format_number(l.page.x(), 6), format_number(l.page.y(), 6), std::to_string(l.band),
                           format_number(l.value, 6), format_number(l.phase, 6), format_number(l.fitted, 6),
                           l.outlier ? "1" : "0"});
    table.write(folder / "lenslets.csv");
    for (const bool along_x : {true, false}) {
        LineChart chart;
        chart.title = std::string("Lenslets against the ") + (along_x ? "x" : "row") + " bands' lines";
        chart.x_label = "phase against the lines (periods; 0: on a line's centre)";
        chart.y_label = "reading / fitted light falloff";
        chart.key_position = "bottom right";
        for (const PitchReading& r : readings) {
            const AxisFit& fit = along_x ? r.x : r.y;
            PlotSeries read{r.name + ": lenslets", {}, {}}, model{r.name + ": fitted profile", {}, {}};
            for (const LensletReading& l : r.lenslets) {
                if (l.band < 0 || l.along_x != along_x || l.outlier) continue;
                read.x.push_back(l.phase - std::floor(l.phase));
                read.y.push_back(l.value / l.light);
            }
            if (read.x.empty()) continue;
            // Sorted by phase: the chart draws a line through them.
            std::vector<std::size_t> order(read.x.size());
            for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
            std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return read.x[a] < read.x[b]; });
            PlotSeries sorted{read.title, {}, {}};
            for (const std::size_t k : order) sorted.x.push_back(read.x[k]), sorted.y.push_back(read.y[k]);
            read = std::move(sorted);
            for (std::size_t k = 0; k <= fit.profile.size(); ++k) {
                model.x.push_back(static_cast<double>(k) / static_cast<double>(fit.profile.size()));
                model.y.push_back(fit.profile[k % fit.profile.size()]);
            }
            chart.series.push_back(read);
            chart.series.push_back(model);
        }
        write_line_chart(chart, folder / (along_x ? "profile_x" : "profile_rows"));
    }
}

}  // namespace rfd::calibrate
