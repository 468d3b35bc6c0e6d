#pragma once
// A display as assembled, not as designed: the printed pattern mounted with an error on the
// lens array (shifted, turned, printed at a slightly wrong pitch: thesis 8.4.1), and the
// spacer between pattern and diffuser a little too thick or too thin.
//
// Frame: the encoding plane's (optics/display.hpp): millimetres, origin on the array's
// axis, x right and y up as the observer sees the display. The pattern as mounted is the
// pattern as encoded, scaled by (1 + pitch_error) about the axis, turned counter-clockwise
// by `rotation` about the axis, then shifted by `shift`:
//     mounted(q) = encoded(p),  p = R(-rotation) (q - shift) / (1 + pitch_error).
// Rotation about the axis (the centre of the array), not a corner: the thesis aligns the
// print by markers at the four corners (8.4.1), so a residual turn is spread symmetrically
// about the centre; a turn about a corner is this turn plus a shift, which the shift sweep
// covers on its own.
//
// Example: MisalignedTransparency mounted(printed, Mounting{{0.05, 0.0}, 0.0, 0.0});
//          DiffuserImage out = DisplaySimulator(design).simulate(mounted, lights, {});

#include <Eigen/Core>

#include "optics/design.hpp"
#include "optics/display.hpp"

namespace rfd::optics {

/// How the pattern sits on the array relative to where the encoder meant it to be.
struct Mounting {
    Eigen::Vector2d shift_mm = Eigen::Vector2d::Zero();  ///< displacement of the print, mm
    double rotation_rad = 0.0;  ///< counter-clockwise turn about the array's axis
    double pitch_error = 0.0;   ///< relative: printed (1 + pitch_error) times too large
};

/// A Transparency presenting another one as mounted with `mounting` (see the header
/// comment). Keeps a reference: `pattern` must outlive it. Thread-safe if `pattern` is.
class MisalignedTransparency final : public Transparency {
public:
    MisalignedTransparency(const Transparency& pattern, const Mounting& mounting);
    int channels() const override { return pattern_.channels(); }
    void sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const override;

    /// The point of the encoded pattern that lies at `point` once mounted.
    Eigen::Vector2d to_pattern(const Eigen::Vector2d& point) const;

private:
    const Transparency& pattern_;
    Mounting mounting_;
    Eigen::Matrix2d inverse_;  // R(-rotation) / (1 + pitch_error)
};

/// `design` with the distance from the pattern to the diffuser changed by `delta_mm`
/// (thicker spacer for delta_mm > 0): a sheet carrying the pattern (Design I's spacer) grows
/// by delta_mm, and every plane behind the pattern plane moves back by delta_mm. Everything
/// in front of the pattern (the lens array, the focus on the pattern) stays. InputError
/// when the change leaves a sheet without thickness or makes parts overlap.
Design with_spacer_error(const Design& design, double delta_mm);

/// The nominal pattern-to-diffuser distance of `design` (Design I: the spacer's
/// thickness), mm. InputError for a design without a diffuser.
double pattern_to_diffuser_mm(const Design& design);

}  // namespace rfd::optics
