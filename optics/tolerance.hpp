#pragma once
// Assembly tolerances of a Design I/II display (issue 5): how far may the print be shifted,
// turned or scaled on the lens array (thesis 8.4.1), and the spacer be off, before the
// picture the display shows changes visibly?
//
// For every kind of error and every value of a sweep 0..max, the display is simulated as
// assembled (misalignment.hpp) under each light on its own, and the pictures at the
// display's resolution (DisplaySimulator::per_lenslet, one value per lenslet) are compared
// with the error-free ones:
//     PSNR = 10 log10(peak^2 / MSE),  peak = largest value of the nominal pictures,
// MSE over every lenslet, channel and light. Each value is tried with both signs and the
// worse PSNR kept, so a tolerance bounds |error|. PSNR is capped at kPsnrCeilingDb (an
// identical picture gives the ceiling, never infinity). The tolerance is where the PSNR
// first drops below the threshold: bracketed by the sweep, then refined by bisection on
// the bracket (assuming the PSNR falls monotonically inside it); the reported value is the
// largest error tried whose PSNR stayed above the threshold.
//
// What to expect (paraxial, offset = B tan(theta) on the pattern, thesis 8.4):
//  - shift s: under direction theta every lenslet samples the pattern at B tan(theta) - s,
//    i.e. shows what it should show for tan(theta') = tan(theta) - s / B;
//  - rotation a and pitch error e: lenslet centre c samples the dot that belongs at
//    c + a (-c_y, c_x) resp. (1 + e) c, a drift growing with the distance from the axis
//    (the moire of 8.4.1), so their tolerances scale with 1 / (lenslets across);
//  - spacer t: the light leaving the pattern travels t further before the diffuser: its
//    spot moves by t tan(theta_s) (theta_s the angle inside the spacer) and its cone
//    widens (blur); Design II's diffuser leaves the image plane of A.
// The shift reported beside the PSNR is the mean displacement of each light's picture on
// the diffuser (intensity centroid, in lenslet pitches): it measures where the light goes
// (the spacer), while the pattern errors change what the light carries, not where it goes.
//
// Example: ToleranceReport r = sweep_tolerances(design, printed, default_lights(optics, Model::Paraxial), {});
//          r.curves[0].tolerance  // largest |shift| in mm with PSNR >= 30 dB

#include <optional>
#include <string>
#include <vector>

#include "optics/design.hpp"
#include "optics/display.hpp"

namespace rfd::optics {

enum class MountingError { Shift, Rotation, PitchError, Spacer };
/// "shift", "rotation", "pitch_error", "spacer".
std::string_view to_string(MountingError kind);

inline constexpr double kPsnrCeilingDb = 100.0;

struct ToleranceOptions {
    double max_shift_mm = 0.0;      ///< along x; 0 leaves the kind out
    double max_rotation_rad = 0.0;  ///< about the axis; 0 leaves it out
    double max_pitch_error = 0.0;   ///< relative (1e-6 = 1 ppm); 0 leaves it out
    double max_spacer_mm = 0.0;     ///< pattern-to-diffuser distance; 0 leaves it out
    int steps = 6;                  ///< sweep values after zero
    int refinements = 4;            ///< bisection steps on the bracket
    double threshold_db = 30.0;
    SimulationOptions simulation;
};

/// Defaults for `design`: each maximum moves the pattern under the outermost lenslet by
/// half a lenslet pitch (shift: pitch / 2; rotation and pitch error: pitch / 2 over the
/// largest lenslet-centre radius), where it shows the neighbour's content; the spacer by a
/// quarter of the pattern-to-diffuser distance.
ToleranceOptions default_tolerance_ranges(const DesignOptics& optics);

/// A few directions inside the field of view: the axis and two at half the wrap-over
/// angle (thesis 8.2.3) along +x and +y, white. (Their mirror images along -x and -y add
/// little: every error is tried with both signs.)
std::vector<DisplayLight> default_tolerance_lights(const DesignOptics& optics, Model model);

struct TolerancePoint {
    double error = 0.0;            ///< mm, radians or relative, by kind (SI-free: as in options)
    double psnr_db = 0.0;          ///< worse of +error and -error, capped at kPsnrCeilingDb
    double shift_lenslets = 0.0;   ///< mean centroid displacement on the diffuser, pitches
};

struct ToleranceCurve {
    MountingError kind = MountingError::Shift;
    std::vector<TolerancePoint> sweep;       ///< 0, max/steps, ..., max
    std::vector<TolerancePoint> refinement;  ///< the bisection's trials
    /// Largest error tried with PSNR >= threshold when the sweep crossed it; nullopt when
    /// the whole sweep stayed above (the tolerance exceeds the maximum).
    std::optional<double> tolerance;
};

struct ToleranceReport {
    double nominal_peak = 0.0;  ///< largest per-lenslet value of the error-free pictures
    std::vector<ToleranceCurve> curves;  ///< in the order shift, rotation, pitch, spacer
};

/// The sweep. InputError for bad ranges (negative or not finite, steps < 1, threshold not
/// finite), for lights the simulator refuses, and when the nominal pictures are black.
/// Progress on stderr. Deterministic: the simulations run one after another in a fixed
/// order (each is parallel inside and deterministic).
ToleranceReport sweep_tolerances(const Design& design, const Transparency& pattern,
                                 const std::vector<DisplayLight>& lights, const ToleranceOptions& options);

/// PSNR (dB, capped at kPsnrCeilingDb) of `pictures` against `nominal`, peak = the largest
/// nominal value; both the same number of same-shaped images.
double stacked_psnr(const std::vector<Image>& nominal, const std::vector<Image>& pictures);

}  // namespace rfd::optics
