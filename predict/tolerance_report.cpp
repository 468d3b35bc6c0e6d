#include "predict/tolerance_report.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>
#include <vector>

#include "core/files.hpp"
#include "core/plot.hpp"
#include "core/text.hpp"

namespace rfd::predict {
namespace {

// How a kind's errors are shown: unit name and factor from the library's value.
struct Display {
    const char* label;
    const char* unit;
    double factor;
    const char* phrase;  // "keep the shift under"
};

Display display_of(optics::MountingError kind) {
    switch (kind) {
        case optics::MountingError::Shift: return {"pattern shift along x", "mm", 1.0, "keep the shift under"};
        case optics::MountingError::Rotation:
            return {"pattern rotation", "deg", 180.0 / std::numbers::pi, "the rotation under"};
        case optics::MountingError::PitchError: return {"pattern pitch error", "ppm", 1e6, "the pitch error under"};
        case optics::MountingError::Spacer: return {"spacer thickness error", "mm", 1.0, "the spacer within"};
    }
    return {"?", "", 1.0, ""};
}

// Four significant digits, but never an exponent: 1.2e+04 ppm reads worse than 12000.
std::string format(double value) { return std::abs(value) >= 1e4 ? format_fixed(value, 0) : format_number(value, 4); }

LineChart curve_chart(const optics::ToleranceCurve& curve, const Display& shown, const ToleranceContext& context) {
    LineChart chart;
    chart.title = std::string("Tolerance: ") + shown.label + " (" + context.design + ")";
    chart.x_label = std::string(shown.label) + " (" + shown.unit + ", worse of +/-)";
    chart.y_label = "PSNR of the per-lenslet picture (dB)";
    chart.y2_label = "picture shift on the diffuser (lenslets)";
    chart.key_position = "top right";
    PlotSeries psnr{"PSNR vs error-free", {}, {}, false};
    PlotSeries threshold{"threshold " + format(context.threshold_db) + " dB", {}, {}, false};
    PlotSeries shift{"picture shift (right axis)", {}, {}, true};
    for (const optics::TolerancePoint& p : curve.sweep) {
        const double x = p.error * shown.factor;
        psnr.x.push_back(x), psnr.y.push_back(p.psnr_db);
        threshold.x.push_back(x), threshold.y.push_back(context.threshold_db);
        shift.x.push_back(x), shift.y.push_back(p.shift_lenslets);
    }
    chart.series = {psnr, threshold, shift};
    if (curve.tolerance) {
        const double t = *curve.tolerance * shown.factor;
        chart.vertical_markers.push_back({t, "tolerance " + format(t) + " " + shown.unit});
    }
    return chart;
}

}  // namespace

ToleranceReportText write_tolerance_report(const std::filesystem::path& folder, const optics::ToleranceReport& report,
                                           const ToleranceContext& context) {
    ensure_directory(folder);
    ToleranceReportText out;
    ToleranceSummary& record = out.summary;
    std::ostringstream table;
    std::vector<std::string> phrases;
    for (const optics::ToleranceCurve& curve : report.curves) {
        const Display shown = display_of(curve.kind);
        const std::string name(optics::to_string(curve.kind));
        ToleranceCurveRecord curve_record{name, shown.unit, 0.0, std::nullopt, {}, {}, name + ".svg"};
        for (const optics::TolerancePoint& p : curve.sweep)
            curve_record.sweep.push_back({p.error * shown.factor, p.psnr_db, p.shift_lenslets});
        for (const optics::TolerancePoint& p : curve.refinement)
            curve_record.refinement.push_back({p.error * shown.factor, p.psnr_db, std::nullopt});
        const double largest = curve.sweep.back().error * shown.factor;
        const std::string verdict =
            curve.tolerance ? format(*curve.tolerance * shown.factor) + " " + shown.unit
                            : format(largest) + " " + shown.unit + " (the whole sweep stayed above the threshold)";
        write_line_chart(curve_chart(curve, shown, context), folder / name);
        phrases.push_back(std::string(shown.phrase) + " " +
                          (curve.tolerance ? format(*curve.tolerance * shown.factor) + " " + shown.unit
                                           : format(largest) + " " + shown.unit + " (or more)"));
        char row[256];
        std::snprintf(row, sizeof row, "  %-24s %s\n", shown.label, verdict.c_str());
        table << row;
        curve_record.max = largest;
        if (curve.tolerance) curve_record.tolerance = *curve.tolerance * shown.factor;
        record.curves.push_back(std::move(curve_record));
    }
    std::string sentence;
    for (std::size_t k = 0; k < phrases.size(); ++k)
        sentence += (k == 0 ? "" : k + 1 == phrases.size() ? " and " : ", ") + phrases[k];
    if (!sentence.empty()) sentence[0] = static_cast<char>(std::toupper(sentence[0]));
    std::ostringstream text;
    text << "Assembly tolerances of '" << context.design << "' for " << context.pattern << " (PSNR >= "
         << format(context.threshold_db) << " dB against the error-free prediction, " << context.lights
         << " light(s), " << context.model << " model):\n"
         << table.str() << sentence << ".\n";
    out.text = text.str();
    write_text_file(folder / "summary.txt", out.text);
    record.design = context.design;
    record.threshold_db = context.threshold_db;
    record.model = context.model;
    record.lights = context.lights;
    record.nominal_peak = report.nominal_peak;
    record.summary = sentence;
    write_summary(folder / "summary.json", record);
    return out;
}

}  // namespace rfd::predict
