#include "predict/verdict.hpp"

#include <algorithm>
#include <cmath>

#include "core/text.hpp"
#include "predict/summaries.hpp"

namespace rfd::predict {
namespace {

std::string db(double value) { return format_fixed(value, 1) + " dB"; }

// The first tolerance finer than assembly by hand (or than a calibrated pitch), worded.
std::optional<std::string> tight_tolerance(const AssemblyTolerances& t, const VerdictRules& rules) {
    if (t.shift_mm && *t.shift_mm < rules.hand_shift_mm)
        return "the pattern shift must stay under " + format_number(*t.shift_mm, 3) + " mm, finer than registration by hand (" +
               format_number(rules.hand_shift_mm) + " mm)";
    if (t.rotation_deg && *t.rotation_deg < rules.hand_rotation_deg)
        return "the pattern rotation must stay under " + format_number(*t.rotation_deg, 3) +
               " deg, finer than registration by hand (" + format_number(rules.hand_rotation_deg) + " deg)";
    if (t.spacer_mm && *t.spacer_mm < rules.hand_spacer_mm)
        return "the spacer must be within " + format_number(*t.spacer_mm, 3) + " mm, finer than a printed part (" +
               format_number(rules.hand_spacer_mm) + " mm)";
    if (t.pitch_ppm && *t.pitch_ppm < rules.calibrated_pitch_ppm)
        return "the lenslet pitch must be known to " + format_number(*t.pitch_ppm, 3) +
               " ppm, finer than the moire sheet calibrates it (" + format_number(rules.calibrated_pitch_ppm) + " ppm)";
    return std::nullopt;
}

}  // namespace

std::string_view to_string(Call call) {
    switch (call) {
    case Call::Go: return "go";
    case Call::Check: return "check";
    case Call::NoGo: return "no-go";
    }
    return "check";
}

std::string Verdict::line() const { return std::string(to_string(call)) + ": " + reason; }
std::string VerdictPart::line() const { return std::string(to_string(call)) + ": " + reason; }

namespace {

// The verdict on this field, the design's warnings aside.
VerdictPart judge_field(const VerdictInputs& inputs, const VerdictRules& rules, Verdict& v);

VerdictPart judge_design(const VerdictInputs& inputs) {
    if (inputs.warnings.empty()) return {Call::Go, "no design warnings"};
    return {Call::Check, "design warning: " + inputs.warnings.front() +
                             (inputs.warnings.size() > 1 ? " (and " + std::to_string(inputs.warnings.size() - 1) + " more)"
                                                         : "")};
}

}  // namespace

Verdict judge(const VerdictInputs& inputs, const VerdictRules& rules) {
    Verdict v;
    v.inputs = inputs;
    v.on_field = judge_field(inputs, rules, v);
    v.on_design = judge_design(inputs);
    const VerdictPart& whole = v.on_field.call == Call::Go ? v.on_design : v.on_field;
    v.call = whole.call;
    v.reason = whole.reason;
    if (v.call == Call::Go) v.reason = v.on_field.reason + ", no design warnings";
    return v;
}

namespace {

VerdictPart judge_field(const VerdictInputs& inputs, const VerdictRules& rules, Verdict& v) {
    double field_peak = 0.0;
    for (const ComparedDirection& d : inputs.directions) field_peak = std::max(field_peak, d.peak);
    // The one PSNR of a display against its field (summaries.hpp); a black field is caught below.
    const auto psnr = [&](const ComparedDirection& d) { return psnr_against_field_db(d.mse, field_peak).value_or(0.0); };
    double sum_fov = 0.0, sum_free = 0.0, min_fov = 1e300;
    const ComparedDirection* worst = nullptr;
    for (const ComparedDirection& d : inputs.directions) {
        if (!d.inside_fov) continue;
        const double p = psnr(d);
        ++v.directions_in_fov;
        sum_fov += p;
        if (p < min_fov) {
            min_fov = p;
            worst = &d;
        }
        if (d.crosstalk_free) {
            ++v.directions_crosstalk_free;
            sum_free += p;
        }
    }
    if (field_peak <= 0.0 || v.directions_in_fov == 0)
        return {Call::Check, field_peak <= 0.0 ? "the field is black in every compared direction: nothing to judge"
                                               : "no compared light lies inside the field of view: nothing to judge"};
    v.psnr_mean_in_fov_db = sum_fov / v.directions_in_fov;
    v.psnr_min_in_fov_db = min_fov;
    if (v.directions_crosstalk_free > 0) v.psnr_mean_crosstalk_free_db = sum_free / v.directions_crosstalk_free;

    if (*v.psnr_mean_in_fov_db < rules.poor_db)
        return {Call::NoGo, "the predicted display matches the field by only " + db(*v.psnr_mean_in_fov_db) +
                                " over the field of view (below " + db(rules.poor_db) +
                                "): the picture would be hard to recognise"};
    if (inputs.tolerances)
        if (auto tight = tight_tolerance(*inputs.tolerances, rules)) return {Call::Check, *tight};
    if (!v.psnr_mean_crosstalk_free_db) return {Call::Check, "no compared light lies inside the crosstalk-free cone"};
    if (*v.psnr_mean_crosstalk_free_db < rules.good_db)
        return {Call::Check, "the crosstalk-free cone shows the field at " + db(*v.psnr_mean_crosstalk_free_db) +
                                 " (below " + db(rules.good_db) + "): look at the predicted pictures before printing"};
    if (min_fov < rules.poor_db)
        return {Call::Check, "at " + format_fixed(worst->display_angle_deg, 1) + " deg from the axis the prediction falls to " +
                                 db(min_fov) + ": that part of the field of view will look wrong"};
    return {Call::Go, "predicted " + db(*v.psnr_mean_crosstalk_free_db) + " in the crosstalk-free cone and at least " +
                          db(min_fov) + " over the field of view" +
                          (inputs.tolerances ? ", with tolerances assembly by hand meets" : "")};
}

}  // namespace

Eigen::Vector2d printed_extent_mm(const optics::Design& design) {
    if (design.macro) return {design.macro->count_x * design.macro->pitch_x, design.macro->count_y * design.macro->pitch_y};
    for (const optics::Plane& plane : design.planes)
        if (plane.part)
            if (const auto* array = std::get_if<optics::LensletArrayPart>(&*plane.part))
                return 2.0 * array->lattice.half_extent();
    return Eigen::Vector2d::Zero();
}

std::string maker_tolerance_text(const AssemblyTolerances& t, const std::vector<std::string>& at_least,
                                 const Eigen::Vector2d& extent_mm) {
    const auto more = [&](const char* kind) {
        return std::find(at_least.begin(), at_least.end(), kind) != at_least.end() ? " or more" : "";
    };
    const auto mm = [](double value) { return format_fixed(value, value < 1.0 ? 2 : 1) + " mm"; };
    std::string out = "shift " + (t.shift_mm ? mm(*t.shift_mm) + more("shift") : std::string("-"));
    out += ", rotation ";
    if (t.rotation_deg) {
        const double corner = 0.5 * extent_mm.norm() * std::sin(*t.rotation_deg * std::acos(-1.0) / 180.0);
        out += format_fixed(*t.rotation_deg, 2) + " deg" + more("rotation") + " (" + mm(corner) + " at the print's corner)";
    } else {
        out += "-";
    }
    out += ", pitch ";
    if (t.pitch_ppm) {
        out += format_fixed(*t.pitch_ppm, 0) + " ppm" + more("pitch_error") + " (the print's size within " +
               mm(*t.pitch_ppm * 1e-6 * extent_mm.x()) + " over its " + format_fixed(extent_mm.x(), 0) +
               " mm: print at 100 %, no fit to page)";
    } else {
        out += "-";
    }
    out += ", spacer " + (t.spacer_mm ? mm(*t.spacer_mm) + more("spacer") : std::string("-"));
    return out;
}

}  // namespace rfd::predict
