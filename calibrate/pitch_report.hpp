#pragma once
// What `rfd calibrate pitch` says and writes: the measured pitch and rotation as text, the
// design file with the measured pitch, and a report folder (every lenslet's reading as CSV,
// the fitted profile against the readings as a chart).
//
// Example: std::fputs(pitch_text(calibration, readings).c_str(), stdout);

#include <filesystem>
#include <string>
#include <vector>

#include "calibrate/pitch.hpp"
#include "optics/design.hpp"

namespace rfd::calibrate {

/// The readings and the result, for a terminal.
std::string pitch_text(const PitchCalibration& calibration, const std::vector<PitchReading>& readings);

/// The design file's text with the lens array's pitch replaced by the measured one (a
/// hexagonal lattice has one pitch: the two axes' estimates weighted by their uncertainties),
/// and a comment saying where it came from. InputError when the file's array table has no
/// pitch line to replace.
std::string calibrated_design_text(const optics::Design& design, const PitchCalibration& calibration,
                                   const std::vector<PitchReading>& readings);

/// lenslets.csv (each lenslet's reading, band, phase and fitted value) and per axis
/// profile_x / profile_rows charts (readings over the light falloff against phase, and G).
void write_pitch_report(const std::vector<PitchReading>& readings, const std::filesystem::path& folder);

}  // namespace rfd::calibrate
