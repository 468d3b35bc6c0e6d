#pragma once
// The printed pattern's shift and turn against the lens array, from photographs of the
// assembled display lit from behind (thesis 8.4.1 aligned markers under drilled corner
// lenslets through a microscope; how to take the photographs: docs/usage.md).
//
// Each lenslet shows on the diffuser how much light the pattern lets through where the lenslet
// focuses: lenslet k at array point c_k reads the pattern at c_k + s, s the light's spot
// offset (about f tan(theta)), and the mounted pattern there is the encoded one at
//     p_k = R(-rotation) (c_k - b) / (1 + pitch_error),   b = shift - s
// (optics/misalignment.hpp). The encoded pattern is known, so every lenslet's reading is a
// sample of it at an unknown point: the photograph is fitted by b, the turn and the pitch
// error (the printer's scale, or a lamp not far enough: its rays are not parallel), with a
// smooth light falloff. One photograph measures b: the shift plus the light's tilt (f tan
// theta, 0.05 mm per degree for Design I). A second one with the display turned by half a
// turn in its plane, the light unchanged, reverses s: the mean of the two is the shift, half
// their difference the light's offset. Or the light's direction is given.
//
// Steps: the lit display is the largest region brighter than Otsu's threshold; the four
// corners of its convex hull (the largest quadrilateral on it) give a first homography from
// the array's lit footprint to the photo, good to a pitch or so; the lenslet images' phase
// over the array's middle, then their centroids, in squares growing from the middle outward,
// refine it (a weighted least-squares homography each time); the whole-lenslet offset of the
// labels is the one that keeps the edge rows on light, not on the holder. So the display's
// corners must be lit: a pattern dark at the array's edge is refused (its readings do not
// follow it). Design II's macro-pixels are even tiles that fill their cells: the lit region
// (every piece of it: the clear marker cells light the corners even where the picture is
// dark) has straight outer edges, whose four longest runs on its hull, then lines fitted
// across its sides, place the array instead. Every lenslet is read over a disc a third of its
// pitch wide about its image; the marker cells (Design I: and their neighbours) are left out.
// A small array (under 100 lenslets: Design II's 26 readings) fits a light falloff linear across it,
// and is tried every way up: a photograph said to be upright must fit best so.
// With the light within about a third of a degree of Design II's axis its corner tiles show their
// markers' crosshair magnified (marker_tiles.hpp): when they do, and the way up is given, they
// are read instead, whatever the picture (its first pass of the sides looks a pitch far and
// not across the corner tiles, which are mostly dark then).
// The photograph may not say which side of the display is up: it is given (upright, or
// turned by half a turn), or each quarter turn is fitted and the best kept.
// The fit: the pattern (its transmittance's mean over the channels, averaged on a grid of
// kPatternStepMm) correlated with the readings over shifts within half a pitch, then Gauss-
// Newton on the shift, turn and scale with the light falloff solved linearly at every step.
// Uncertainties: the fit's own, or the delete-a-group jackknife's over 8 groups when larger.
//
// Where it stops (InputError, saying which): no lit display in view, a pattern the readings do
// not follow (correlation under kMinCorrelation: another pattern, blurred or dark), two
// quarter turns that fit about as well (a pattern too plain to say which way is up), a second
// shift that fits within 5 noise sigmas of the best (lenslet images symmetric about their
// centres read the same with the shift mirrored), or a shift less certain than
// kMaxShiftSigmaMm along either axis (a pattern without detail along it: vertical bars).
//
// Example: PatternMap map(printed, design);
//          RegistrationReading r = read_registration_photo(photo, "photo.jpg", design, map);

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "optics/design.hpp"
#include "optics/display.hpp"

namespace rfd::calibrate {

inline constexpr double kPatternStepMm = 0.04;
inline constexpr double kMinCorrelation = 0.9;
inline constexpr double kMaxShiftSigmaMm = 0.03;

/// The printed pattern's transmittance (mean over its channels) averaged on a grid of
/// kPatternStepMm over the array, bilinear between: what a lenslet's spot reads.
class PatternMap {
public:
    PatternMap(const optics::Transparency& printed, const optics::Design& design);
    /// At a point of the encoding plane (mm); 0 off the grid.
    double at(const Eigen::Vector2d& point) const;

private:
    Eigen::Vector2d origin_;  // point of sample (0, 0)
    int width_ = 0, height_ = 0;
    std::vector<float> values_;
};

/// One lenslet's reading, for the picture of the fit.
struct RegistrationLenslet {
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();  ///< array frame, mm
    double value = 0.0;                                ///< linear
    double fitted = 0.0;                               ///< the model's value
};

/// What one photograph says.
struct RegistrationReading {
    std::string name;
    int quarter_turns = 0;   ///< of the array in the photograph (counter-clockwise), 0..3
    Eigen::Vector2d apparent_shift = Eigen::Vector2d::Zero();  ///< b: the shift less the light's spot offset, mm
    double rotation_rad = 0.0;
    double pitch_error = 0.0;
    Eigen::Matrix4d covariance = Eigen::Matrix4d::Zero();  ///< of (b_x, b_y, rotation, pitch_error)
    double correlation = 0.0;       ///< of the readings and the model, at the best quarter turn
    double runner_up = 0.0;         ///< the next best quarter turn's (NaN: one was given)
    double rms = 0.0;               ///< residual over the mean reading
    double mm_per_pixel = 0.0;      ///< on the display, at its centre
    Eigen::Matrix3d array_to_photo = Eigen::Matrix3d::Identity();  ///< where the lenslets' light is seen
    std::vector<RegistrationLenslet> lenslets;
    /// Design II near the axis: the corner tiles' bins read as pictures of their markers
    /// (marker_tiles.hpp), instead of the lenslets; 0 otherwise.
    std::size_t marker_bins = 0;
};

/// InputError naming the design file when its array is too small to measure the registration
/// from: fewer than 16 lenslets away from its corner markers (Design II's 6 x 5 has 26).
void check_registration_readable(const optics::Design& design);

/// Reads one photograph (linear; any channels) of `design` assembled with the pattern `map`
/// was made from, the display turned by `quarter_turns` (counter-clockwise, 0..3: 0 is upright
/// within 45 deg) in the picture, or, when not given, by whichever fits best. InputError naming
/// `name` where it cannot measure (see the header comment).
RegistrationReading read_registration_photo(const Image& photo, const std::string& name,
                                            const optics::Design& design, const PatternMap& map,
                                            std::optional<int> quarter_turns = std::nullopt);

/// Where the light's spot falls on the pattern, from the lenslet's centre, for a light of
/// direction of travel `light` (z > 0): the mean over the lenslet's rays (exact optics), mm.
Eigen::Vector2d spot_offset(const optics::Design& design, const Eigen::Vector3d& light);

/// The pattern's mounting error over all photographs.
struct Registration {
    Eigen::Vector2d shift_mm = Eigen::Vector2d::Zero();
    Eigen::Vector2d sigma_shift_mm = Eigen::Vector2d::Zero();
    double rotation_deg = 0.0, sigma_rotation_deg = 0.0;
    double pitch_error = 0.0, sigma_pitch_error = 0.0;
    /// How the light's spot offset was taken out: "given", "turned pair" (measured: then
    /// `spot` holds it) or "assumed head-on".
    std::string light;
    Eigen::Vector2d spot = Eigen::Vector2d::Zero();  ///< the light's spot offset, mm
};

/// Combines readings: with `light` given (in the display's frame, the same for every
/// photograph), each photograph's b corrected by its spot offset; otherwise photographs turned
/// by half a turn against the first averaged with it (as many of each way up, weighted
/// equally), or, with no such pair, the light taken as head-on.
Registration combine_registration(const optics::Design& design, const std::vector<RegistrationReading>& readings,
                                  const std::optional<Eigen::Vector3d>& light);

}  // namespace rfd::calibrate

namespace rfd::calibrate {

/// The assembly tolerances to judge against (from `rfd simulate tolerance`), if known.
struct RegistrationTolerances {
    std::optional<double> shift_mm, rotation_deg;
};

/// Whether the shift (its length) and the turn are inside `tolerances`; nullopt when neither
/// is known.
std::optional<bool> inside_tolerances(const Registration& registration, const RegistrationTolerances& tolerances);

/// What `rfd calibrate registration` prints: each photograph's fit, the combined shift, turn
/// and scale with uncertainties, whether they are inside `tolerances`, and what to do.
std::string registration_text(const Registration& registration, const std::vector<RegistrationReading>& readings,
                              const RegistrationTolerances& tolerances);

}  // namespace rfd::calibrate
