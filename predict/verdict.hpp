#pragma once
// The verdict: is this display, for this field and printer, worth printing? One line
// (go / check / no-go and the reason) over the figures it rests on: the predicted PSNR over
// the field of view, the crosstalk-free cone, the assembly tolerances and the design-rule
// warnings (docs/methods.md, "The verdict").
//
// PSNR here is against the brightest value the field shows in any of the compared
// directions, not each direction's own peak: a direction where the field is dark (a test
// field lights one letter per direction) must not count a faint residue as a failure.
//
// Example:
//   const Verdict v = judge(inputs);
//   std::puts(v.line().c_str());     // "check: the pattern shift must stay under 0.08 mm ..."

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "optics/design.hpp"

namespace rfd::predict {

/// One light direction of `rfd simulate compare`.
struct ComparedDirection {
    double display_angle_deg = 0.0;
    bool inside_fov = false;
    bool crosstalk_free = false;
    double mse = 0.0;    ///< mean squared error against the relit field
    double peak = 0.0;   ///< the relit field's largest value in this direction
};

/// What `rfd simulate tolerance` found: the largest errors that keep PSNR above its
/// threshold (nullopt: the sweep never fell below it).
struct AssemblyTolerances {
    std::optional<double> shift_mm, rotation_deg, pitch_ppm, spacer_mm;
};

struct VerdictInputs {
    std::string design;
    std::optional<double> field_of_view_deg;         ///< full cone without wrap-over
    std::optional<double> crosstalk_free_cone_deg;   ///< full cone without crosstalk
    std::vector<ComparedDirection> directions;
    std::optional<AssemblyTolerances> tolerances;
    std::vector<std::string> warnings;               ///< the design's rules broken
};

enum class Call { Go, Check, NoGo };

/// The thresholds the verdict applies, named so docs and messages quote one place.
struct VerdictRules {
    double good_db = 30.0;          ///< mean PSNR in the crosstalk-free cone for "go"
    double poor_db = 20.0;          ///< mean PSNR in the field of view below which "no-go"
    double hand_shift_mm = 0.1;     ///< registration by eye through a loupe, markers on lenslets
    double hand_rotation_deg = 0.25;
    double hand_spacer_mm = 0.1;    ///< a printed spacer's thickness, FDM layer-level
    double calibrated_pitch_ppm = 500.0;  ///< half a step of the default moire sheet (0.1 %)
};

/// One part of the verdict: a call and its reason.
struct VerdictPart {
    Call call = Call::Check;
    std::string reason;
    std::string line() const;  ///< "go: ..."
};

struct Verdict {
    /// The whole: the field part where it is not go, the design part otherwise.
    Call call = Call::Check;
    std::string reason;
    /// On this field with this design as printed: the predicted PSNR, the crosstalk-free
    /// cone, the assembly tolerances; whatever the design's own warnings.
    VerdictPart on_field;
    /// On the design itself: its rules (`design show`'s warnings), whatever the field.
    VerdictPart on_design;
    std::optional<double> psnr_mean_in_fov_db, psnr_min_in_fov_db, psnr_mean_crosstalk_free_db;
    int directions_in_fov = 0, directions_crosstalk_free = 0;
    VerdictInputs inputs;

    /// "go: ..." / "check: ..." / "no-go: ...".
    std::string line() const;
};

Verdict judge(const VerdictInputs& inputs, const VerdictRules& rules = {});

std::string_view to_string(Call call);

/// The printed pattern's width and height, mm: the lenslet array's extent (Design IV: its
/// grid of macro-pixels), what a pitch error stretches.
Eigen::Vector2d printed_extent_mm(const optics::Design& design);

/// The tolerances as a maker acts on them: the shift and spacer in mm, the rotation in
/// degrees and as mm at the print's corner, the pitch error as ppm and as mm over the
/// print's width with "print at 100 %" (a driver's fit-to-page scales by percents).
/// `at_least`: the kinds ("shift", "rotation", "pitch_error", "spacer") the sweep only
/// bounded from below.
std::string maker_tolerance_text(const AssemblyTolerances& t, const std::vector<std::string>& at_least,
                                 const Eigen::Vector2d& extent_mm);

}  // namespace rfd::predict
