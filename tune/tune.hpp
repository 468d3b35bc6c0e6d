#pragma once
// `rfd design tune`: the free parameters of a design (the z of its planes) chosen to meet
// the targets a maker names while making one measure as large as the parts allow.
//
// The measures are those `rfd design show` reports (optics/analysis.hpp): light efficiency
// on the axis and at half the field of view (exact rays through the whole stack), the field
// of view, and the planes the design needs in focus or conjugate (thesis figures 8.5, 8.8,
// 8.11), each with the tolerance beyond which `design show` warns.
//
// The optimiser is NLopt's COBYLA (Powell 1994): derivative-free, bounded, with nonlinear
// inequality constraints. Derivative-free because efficiency counts the rays that arrive
// (a step function of the spacings); constraints because "every plane where the optics want
// it" and "no part overlaps the next" are conditions, not costs. COBYLA is local, so it runs
// from the design as given and from `starts - 1` further points drawn with the seed; the
// best feasible design any run visited wins. Deterministic for a given seed.
//
// Example: TuneSpec spec = default_spec(design);
//          TuneResult result = tune_design(design, spec);

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "optics/analysis.hpp"
#include "optics/design.hpp"

namespace rfd::tune {

/// What a target or the objective can name.
enum class Measure {
    EfficiencyOnAxis,     ///< fraction of a full bundle on the axis reaching the last surface
    EfficiencyAtHalfFov,  ///< the same at half the field of view
    FieldOfView,          ///< full cone without wrap-over, degrees (exact)
    EfficiencyMean,       ///< the efficiency averaged over directions filling the field of view
};
std::string_view to_string(Measure measure);
/// All names, for help texts: "efficiency_on_axis, ...".
std::string measure_names();

/// One design's measures.
struct Measures {
    double efficiency_on_axis = 0;
    double efficiency_at_half_fov = 0;
    double field_of_view_deg = 0;  ///< 2 x the search limit when nothing wraps over
    double efficiency_mean = 0;    ///< over a 7 x 7 grid of directions, those inside 0.9 x half the FOV
    std::vector<optics::ConjugateCheck> planes;
    std::vector<std::string> warnings;

    double value(Measure measure) const;
};
/// `with_mean`: also the mean efficiency over the field (37 bundles: the costliest measure).
Measures measure(const optics::Design& design, bool with_mean = true);

/// "field_of_view_deg >= 25": a measure kept at or above (or at or below) a value.
struct Target {
    Measure measure = Measure::EfficiencyOnAxis;
    bool at_least = true;
    double value = 0;
};
/// Parses "NAME>=VALUE" or "NAME<=VALUE"; throws InputError naming the text otherwise.
Target parse_target(std::string_view text);
std::string to_string(const Target& target);

/// A spacing the tuner may change: the air between plane `plane`'s part and the part in
/// front of it, within [lower, upper] mm. The planes behind move with it, so parts never
/// overlap and every spacing not named keeps its length.
struct FreeSpacing {
    std::string plane;
    double lower = 0, upper = 0;
};

/// The air in front of each plane's part (0 for the first plane), mm.
std::vector<double> spacings(const optics::Design& design);

struct TuneSpec {
    std::vector<FreeSpacing> free;
    std::vector<Target> targets;
    /// The planes the design needs in focus or conjugate that must lie within `design
    /// show`'s tolerance of where the optics want them, by key (ConjugateCheck::key).
    std::vector<std::string> planes;
    /// Those planes held within this fraction of `design show`'s tolerance (1: as it warns).
    double tolerance_scale = 1.0;
    Measure maximise = Measure::EfficiencyOnAxis;
    int starts = 8;
    int evaluations_per_start = 200;
    std::uint64_t seed = 1;
};

/// The spacing in front of every plane but the first free, from min_gap_mm to range_mm
/// longer than it is; every plane in place; efficiency on the axis maximised.
TuneSpec default_spec(const optics::Design& design, double range_mm, double min_gap_mm);
/// The same for the named planes' spacings only.
FreeSpacing free_spacing(const optics::Design& design, const std::string& plane, double range_mm, double min_gap_mm);

/// The keys of every plane condition the design has ("meso-focus", ...).
std::vector<std::string> plane_keys(const optics::Design& design);

/// Checks the spec against the design: planes that exist and are not the first, ranges
/// that are not empty, plane conditions the design has. Throws InputError naming the option.
void check_spec(const optics::Design& design, const TuneSpec& spec);

/// A condition of the problem at the tuned design: its name and its slack (>= 0 holds;
/// in the condition's own unit: mm for spacings and planes).
struct Condition {
    std::string name;
    double slack = 0;
    bool binding = false;  ///< holds with (almost) no slack: it limits the objective
};

struct TuneResult {
    optics::Design design;        ///< the tuned design (the given one if nothing better)
    Measures before, after;
    std::vector<double> spacing_before, spacing_after;  ///< per free spacing, mm
    std::vector<Condition> conditions;  ///< planes, targets and spacings' ranges at the end
    bool feasible = false;        ///< every condition holds at the tuned design
    bool given_was_feasible = false;
    int evaluations = 0;
};
TuneResult tune_design(const optics::Design& design, const TuneSpec& spec);

/// The design file's text with the free planes' z_mm replaced by the tuned values and a
/// header comment saying what was tuned, against what and from which file. The result
/// parses to the tuned design (checked; RFD_CHECK otherwise).
std::string tuned_design_text(const std::string& original_text, const optics::Design& original,
                              const TuneResult& result, const std::string& header);

}  // namespace rfd::tune
