#include "calibrate/tone_report.hpp"

#include <cmath>

#include "core/csv.hpp"
#include "core/files.hpp"
#include "core/plot.hpp"
#include "core/text.hpp"

namespace rfd::calibrate {
std::string tone_text(const ToneCalibration& calibration, const std::vector<WedgeReading>& readings,
                      const print::PrinterProfile& nominal) {
    std::string out;
    for (const WedgeReading& r : readings)
        out += format_text(
            "%s: %.3f mm a pixel%s, bare film at %.1f %% of the "
            "scale, light varies %.1f %% over the "
            "sheet (%.2f %% RMS off its smooth fit)\n",
            r.name.c_str(), r.mm_per_pixel, r.mirrored ? ", seen from the film's back" : "", 100.0 * r.exposure,
            100.0 * r.light_spread, 100.0 * r.light_residual);
    out +=
        "  code    ink   measured T (+-)        density   profile T   power "
        "law T\n";
    const print::PrinterProfile power = calibration.power_law();
    for (const PatchReading& p : calibration.patches)
        out += format_text("  %4d  %.3f   %.4f (%.4f)   %7.3f   %9.4f   %11.4f\n", p.code, p.ink, p.transmittance,
                           p.standard_error, -std::log10(std::max(p.transmittance, 1e-6)), nominal.transmittance(p.ink),
                           power.transmittance(p.ink));
    const print::PrinterProfile& profile = calibration.profile;
    out += format_text(
        "max_density %.3f (was %.3f), black_level %.4f (was %.4f); power law "
        "gamma %.3f (was %.3f) "
        "departs %.4f RMS from the measurements, the old profile %.4f\n",
        profile.max_density, nominal.max_density, profile.black_level, nominal.black_level, calibration.power_law_gamma,
        nominal.gamma, calibration.power_law_rms, calibration.nominal_rms);
    return out;
}

void write_tone_report(const ToneCalibration& calibration, const print::PrinterProfile& nominal,
                       const std::filesystem::path& folder) {
    ensure_directory(folder);
    const print::PrinterProfile power = calibration.power_law();
    CsvTable table({"code", "ink", "measured_transmittance", "standard_error", "density", "profile_transmittance",
                    "power_law_transmittance", "calibrated_transmittance"});
    LineChart chart;
    chart.title = "Tone curve of " + calibration.profile.name;
    chart.x_label = "ink v (1 - code / 255)";
    chart.y_label = "transmittance against bare film";
    chart.log_y = true;
    chart.key_position = "bottom left";
    PlotSeries measured{"measured", {}, {}}, old{"profile before", {}, {}}, fitted{"power law fitted", {}, {}},
        calibrated{"profile after (measured curve)", {}, {}};
    for (const PatchReading& p : calibration.patches) {
        table.add_row({std::to_string(p.code), format_number(p.ink, 6), format_number(p.transmittance, 6),
                       format_number(p.standard_error, 6),
                       format_number(-std::log10(std::max(p.transmittance, 1e-6)), 6),
                       format_number(nominal.transmittance(p.ink), 6), format_number(power.transmittance(p.ink), 6),
                       format_number(calibration.profile.transmittance(p.ink), 6)});
        measured.x.push_back(p.ink);
        measured.y.push_back(p.transmittance);
    }
    constexpr int kCurveSteps = 100;
    for (int k = 0; k <= kCurveSteps; ++k) {
        const double v = static_cast<double>(k) / kCurveSteps;
        for (auto [series, profile] :
             {std::pair{&old, &nominal}, std::pair{&fitted, &power}, std::pair{&calibrated, &calibration.profile}}) {
            series->x.push_back(v);
            series->y.push_back(profile->transmittance(v));
        }
    }
    chart.series = {measured, old, fitted, calibrated};
    table.write(folder / "tone.csv");
    write_line_chart(chart, folder / "tone_chart");
}

}  // namespace rfd::calibrate
