#pragma once
// What `rfd calibrate tone` shows and writes: the patches as a table (text and CSV), the
// measured curve against the profile it replaces and the fitted power law (a chart), and each
// scan's view of the sheet with the places that were measured (a picture).
//
// Example: std::fputs(tone_text(calibration, readings, nominal).c_str(), stdout);

#include <filesystem>
#include <string>
#include <vector>

#include "calibrate/tone.hpp"

namespace rfd::calibrate {

/// The report on the terminal: per scan how it was seen, per patch the measurement, and the
/// profile's new values.
std::string tone_text(const ToneCalibration& calibration, const std::vector<WedgeReading>& readings,
                      const print::PrinterProfile& nominal);

/// tone.csv (per patch: code, ink, measured transmittance and error, density, the nominal
/// profile's, the power law's and the new profile's transmittance) and the chart tone_chart.png
/// (and .svg, .gp, .csv as tone_chart.*) in `folder`. ToolError when gnuplot is missing, after
/// the CSV is written.
void write_tone_report(const ToneCalibration& calibration, const print::PrinterProfile& nominal,
                       const std::filesystem::path& folder);

}  // namespace rfd::calibrate
