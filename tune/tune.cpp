#include "tune/tune.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>

#include <nlopt.hpp>

#include "core/error.hpp"
#include "core/progress.hpp"
#include "core/text.hpp"
#include "core/units.hpp"

namespace rfd::tune {
namespace {

constexpr Measure kMeasures[] = {Measure::EfficiencyOnAxis, Measure::EfficiencyAtHalfFov, Measure::FieldOfView,
                                 Measure::EfficiencyMean};

// Mean fraction of a full bundle reaching the last surface over directions that fill the
// cone of `half_angle_deg`: a 7 x 7 grid in (tan x, tan y), those inside the cone. On a
// lattice with an even count the axis is a border between lenslets (Designs III/IV: between
// two incident bins), the worst direction there is; the mean says what a user sees overall.
double mean_efficiency(const optics::DesignOptics& optics, double half_angle_deg) {
    constexpr int kGrid = 7;
    constexpr int kRays = 21;
    const double reach = std::tan(degrees_to_radians(half_angle_deg));
    double sum = 0.0;
    int count = 0;
    for (int iy = 0; iy < kGrid; ++iy)
        for (int ix = 0; ix < kGrid; ++ix) {
            const double tx = reach * (2.0 * ix / (kGrid - 1) - 1.0);
            const double ty = reach * (2.0 * iy / (kGrid - 1) - 1.0);
            if (tx * tx + ty * ty > reach * reach * (1 + 1e-12)) continue;
            const Eigen::Vector3d d = Eigen::Vector3d(tx, ty, 1.0).normalized();
            const auto bundle = optics.trace_bundle(d, optics.centre_cell(), kRays);
            sum += bundle.rays ? double(bundle.arrived) / double(bundle.rays) : 0.0;
            ++count;
        }
    return sum / count;
}

// A constraint's unit for COBYLA (its value is divided by it), so that one step of each
// means about as much: a percent of efficiency, a degree of field of view.
double unit_of(Measure measure) { return measure == Measure::FieldOfView ? 1.0 : 0.01; }

// Written to 0.1 um, the precision of the presets' z_mm; the tuned design is measured at
// exactly the values its file will hold.
constexpr double kWrittenStep = 1e-4;
double as_written(double z) { return std::round(z / kWrittenStep) * kWrittenStep; }

// A constraint value this close to zero still holds (COBYLA ends on the boundary).
constexpr double kFeasible = 1e-6;
// The optimiser holds each plane 1 um inside its tolerance, so that writing z to 0.1 um
// (which moves a plane and the place the optics want it by less) cannot step outside.
constexpr double kPlaneMargin = 1e-3;

std::size_t plane_index(const optics::Design& design, const std::string& name) {
    for (std::size_t k = 0; k < design.planes.size(); ++k)
        if (design.planes[k].name == name) return k;
    return design.planes.size();
}

// The problem as NLopt sees it: x is the length of each free spacing.
class Problem {
public:
    Problem(const optics::Design& design, const TuneSpec& spec)
        : design_(design), spec_(spec), given_(spacings(design)) {
        for (const auto& free : spec.free) index_.push_back(plane_index(design, free.plane));
        uses_mean_ = spec.maximise == Measure::EfficiencyMean;
        for (const auto& target : spec.targets) uses_mean_ = uses_mean_ || target.measure == Measure::EfficiencyMean;
        const Measures given = measure(design, false);
        for (std::size_t k = 0; k < given.planes.size(); ++k)
            if (std::find(spec.planes.begin(), spec.planes.end(), given.planes[k].key) != spec.planes.end())
                checks_.push_back(k);
    }

    std::size_t dimension() const { return index_.size(); }
    std::size_t constraint_count() const { return 2 * checks_.size() + spec_.targets.size(); }

    // The design with the free spacings set to x, every plane behind a spacing moved with it.
    optics::Design at(const std::vector<double>& x) const {
        std::vector<double> gap = given_;
        for (std::size_t k = 0; k < x.size(); ++k) gap[index_[k]] = x[k];
        optics::Design design = design_;
        for (std::size_t k = 1; k < design.planes.size(); ++k) {
            auto& plane = design.planes[k];
            const double front_offset = optics::axial_extent(plane)[0] - plane.z;
            plane.z = optics::axial_extent(design.planes[k - 1])[1] + gap[k] - front_offset;
        }
        return design;
    }

    // One evaluation: objective (to minimise) and constraints (<= 0 holds), recorded.
    double evaluate(const std::vector<double>& x, std::vector<double>* constraints) {
        const Measures m = measure(at(x), uses_mean_);
        std::vector<double> c;
        for (std::size_t k : checks_) {
            const auto& check = m.planes[k];
            const double miss = check.plane_z - check.target_z;
            if (!std::isfinite(miss)) {  // imaged to infinity: as far from the plane as can be
                c.push_back(1e3);
                c.push_back(1e3);
            } else {
                const double tolerance = spec_.tolerance_scale * check.tolerance;
                const double within = tolerance - kPlaneMargin;
                c.push_back((miss - within) / tolerance);
                c.push_back((-miss - within) / tolerance);
            }
        }
        for (const auto& target : spec_.targets) {
            const double v = m.value(target.measure);
            c.push_back((target.at_least ? target.value - v : v - target.value) / unit_of(target.measure));
        }
        const double objective = -m.value(spec_.maximise) / unit_of(spec_.maximise);
        const double violation = c.empty() ? 0.0 : *std::max_element(c.begin(), c.end());
        ++evaluations_;
        const bool feasible = violation <= kFeasible;
        const bool better = feasible ? (!best_feasible_ || objective < best_objective_)
                                     : (!best_feasible_ && violation < best_violation_);
        if (better) {
            best_x_ = x;
            best_objective_ = objective;
            best_violation_ = violation;
            best_feasible_ = feasible;
        }
        if (constraints) *constraints = std::move(c);
        return objective;
    }

    const std::vector<double>& best_x() const { return best_x_; }
    int evaluations() const { return evaluations_; }
    /// Indices into Measures::planes of the conditions held.
    const std::vector<std::size_t>& checks() const { return checks_; }

private:
    const optics::Design& design_;
    const TuneSpec& spec_;
    std::vector<double> given_;
    std::vector<std::size_t> index_;
    std::vector<std::size_t> checks_;
    bool uses_mean_ = false;
    int evaluations_ = 0;
    std::vector<double> best_x_;
    double best_objective_ = std::numeric_limits<double>::infinity();
    double best_violation_ = std::numeric_limits<double>::infinity();
    bool best_feasible_ = false;
};

// A uniform number in [0, 1) from the generator's raw 64 bits: the standard fixes
// mt19937_64's sequence, not uniform_real_distribution's, and starts must not depend on
// the library that built rfd.
double unit_draw(std::mt19937_64& random) { return double(random() >> 11) * 0x1.0p-53; }

std::vector<double> free_spacings(const optics::Design& design, const TuneSpec& spec) {
    const std::vector<double> all = spacings(design);
    std::vector<double> x;
    for (const auto& free : spec.free) x.push_back(all[plane_index(design, free.plane)]);
    return x;
}

}  // namespace

std::string_view to_string(Measure measure) {
    switch (measure) {
        case Measure::EfficiencyOnAxis: return "efficiency_on_axis";
        case Measure::EfficiencyAtHalfFov: return "efficiency_at_half_fov";
        case Measure::FieldOfView: return "field_of_view_deg";
        case Measure::EfficiencyMean: return "efficiency_mean";
    }
    return "?";
}

std::string measure_names() {
    std::string out;
    for (Measure m : kMeasures) out += (out.empty() ? "" : ", ") + std::string(to_string(m));
    return out;
}

double Measures::value(Measure measure) const {
    switch (measure) {
        case Measure::EfficiencyOnAxis: return efficiency_on_axis;
        case Measure::EfficiencyAtHalfFov: return efficiency_at_half_fov;
        case Measure::FieldOfView: return field_of_view_deg;
        case Measure::EfficiencyMean: return efficiency_mean;
    }
    return 0.0;
}

Measures measure(const optics::Design& design, bool with_mean) {
    const optics::DesignOptics optics(design);
    const optics::DesignSummary summary = optics::summarise(optics);
    Measures m;
    m.efficiency_on_axis = summary.efficiency_on_axis;
    m.efficiency_at_half_fov = summary.efficiency_at_half_fov;
    m.field_of_view_deg = summary.field_of_view_deg.value_or(2.0 * optics::kWrapOverSearchLimitDeg);
    m.efficiency_mean = with_mean ? mean_efficiency(optics, 0.45 * m.field_of_view_deg) : 0.0;
    m.planes = summary.conjugates;
    m.warnings = summary.warnings;
    return m;
}

Target parse_target(std::string_view text) {
    const bool at_least = text.find(">=") != std::string_view::npos;
    const std::size_t op = text.find(at_least ? ">=" : "<=");
    if (op == std::string_view::npos)
        throw InputError("--target '" + std::string(text) + "': expected NAME>=VALUE or NAME<=VALUE, NAME one of " +
                         measure_names());
    const std::string name(text.substr(0, op));
    const std::string number(text.substr(op + 2));
    Target target;
    target.at_least = at_least;
    bool known = false;
    for (Measure m : kMeasures)
        if (to_string(m) == name) {
            target.measure = m;
            known = true;
        }
    if (!known)
        throw InputError("--target '" + std::string(text) + "': unknown measure '" + name + "'; expected one of " +
                         measure_names());
    std::size_t used = 0;
    try {
        target.value = std::stod(number, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used == 0 || used != number.size() || !std::isfinite(target.value))
        throw InputError("--target '" + std::string(text) + "': '" + number + "' is not a number");
    return target;
}

std::string to_string(const Target& target) {
    return std::string(to_string(target.measure)) + (target.at_least ? " >= " : " <= ") + format_number(target.value);
}

std::vector<double> spacings(const optics::Design& design) {
    std::vector<double> gap(design.planes.size(), 0.0);
    for (std::size_t k = 1; k < design.planes.size(); ++k)
        gap[k] = optics::axial_extent(design.planes[k])[0] - optics::axial_extent(design.planes[k - 1])[1];
    return gap;
}

FreeSpacing free_spacing(const optics::Design& design, const std::string& plane, double range_mm,
                         double min_gap_mm) {
    const std::size_t k = plane_index(design, plane);
    const double now = k < design.planes.size() ? spacings(design)[k] : 0.0;
    return {plane, std::min(min_gap_mm, now), now + range_mm};
}

std::vector<std::string> plane_keys(const optics::Design& design) {
    std::vector<std::string> keys;
    for (const auto& check : measure(design, false).planes) keys.push_back(check.key);
    return keys;
}

TuneSpec default_spec(const optics::Design& design, double range_mm, double min_gap_mm) {
    TuneSpec spec;
    spec.planes = plane_keys(design);
    for (std::size_t k = 1; k < design.planes.size(); ++k)
        spec.free.push_back(free_spacing(design, design.planes[k].name, range_mm, min_gap_mm));
    return spec;
}

void check_spec(const optics::Design& design, const TuneSpec& spec) {
    if (spec.free.empty()) throw InputError("--free: no plane to move");
    for (const auto& free : spec.free) {
        const std::size_t k = plane_index(design, free.plane);
        if (k == design.planes.size())
            throw InputError(SourceLocation{design.file}, "--free: the design has no plane '" + free.plane + "'");
        if (k == 0)
            throw InputError(SourceLocation{design.file},
                             "--free: plane " + free.plane + " is the first plane: no part lies in front of it");
        if (!(free.lower < free.upper))
            throw InputError("--free: plane " + free.plane + " has an empty range");
    }
    const std::vector<std::string> keys = plane_keys(design);
    for (const auto& key : spec.planes)
        if (std::find(keys.begin(), keys.end(), key) == keys.end()) {
            std::string known;
            for (const auto& k : keys) known += (known.empty() ? "" : ", ") + k;
            throw InputError(SourceLocation{design.file},
                             "--planes: the design has no plane condition '" + key + "'; it has " + known);
        }
    for (std::size_t a = 0; a < spec.free.size(); ++a)
        for (std::size_t b = a + 1; b < spec.free.size(); ++b)
            if (spec.free[a].plane == spec.free[b].plane)
                throw InputError("--free: plane " + spec.free[a].plane + " is named twice");
}

TuneResult tune_design(const optics::Design& design, const TuneSpec& spec) {
    check_spec(design, spec);
    Problem problem(design, spec);
    const std::size_t n = problem.dimension();
    std::vector<double> lower, upper;
    for (const auto& free : spec.free) {
        lower.push_back(free.lower);
        upper.push_back(free.upper);
    }

    TuneResult result;
    result.before = measure(design);
    result.spacing_before = free_spacings(design, spec);
    problem.evaluate(result.spacing_before, nullptr);

    std::mt19937_64 random(spec.seed);
    Progress progress("tuning", static_cast<std::size_t>(spec.starts));
    for (int start = 0; start < spec.starts; ++start) {
        std::vector<double> x = result.spacing_before;
        if (start > 0)
            for (std::size_t k = 0; k < n; ++k) x[k] = lower[k] + unit_draw(random) * (upper[k] - lower[k]);
        for (std::size_t k = 0; k < n; ++k) x[k] = std::clamp(x[k], lower[k], upper[k]);

        // Phase 1: reach the conditions. COBYLA from far outside them wanders (the rays'
        // count is flat there, the planes' misses are not), so BOBYQA first minimises the
        // squared violations, a smooth function of the spacings, and COBYLA starts where
        // they hold (or as near as BOBYQA came).
        if (problem.constraint_count() > 0) {
            nlopt::opt reach(nlopt::LN_BOBYQA, static_cast<unsigned>(n));
            reach.set_lower_bounds(lower);
            reach.set_upper_bounds(upper);
            reach.set_xtol_abs(std::vector<double>(n, 0.1 * kWrittenStep));
            reach.set_stopval(0.0);
            reach.set_maxeval(spec.evaluations_per_start);
            reach.set_min_objective(
                [](unsigned, const double* xs, double*, void* data) {
                    auto* tuned = static_cast<Problem*>(data);
                    std::vector<double> c;
                    tuned->evaluate(std::vector<double>(xs, xs + tuned->dimension()), &c);
                    double sum = 0.0;
                    for (double v : c) sum += v > 0 ? v * v : 0.0;
                    return sum;
                },
                &problem);
            double violation = 0.0;
            try {
                reach.optimize(x, violation);
            } catch (const nlopt::roundoff_limited&) {
            } catch (const std::runtime_error& failure) {
                RFD_CHECK_MSG(false, failure.what());
            }
        }

        nlopt::opt opt(nlopt::LN_COBYLA, static_cast<unsigned>(n));
        opt.set_lower_bounds(lower);
        opt.set_upper_bounds(upper);
        std::vector<double> step(n);
        for (std::size_t k = 0; k < n; ++k) step[k] = std::min(1.0, 0.25 * (upper[k] - lower[k]));
        opt.set_initial_step(step);
        opt.set_xtol_abs(std::vector<double>(n, 0.1 * kWrittenStep));
        opt.set_maxeval(spec.evaluations_per_start);
        // NLopt's C++ wrapper calls one function per constraint; the problem evaluates all of
        // them at once, so the objective caches its constraints for the calls that follow.
        struct Cache {
            Problem* problem;
            std::vector<double> x;
            std::vector<double> constraints;
        } cache{&problem, {}, {}};
        opt.set_min_objective(
            [](unsigned, const double* xs, double*, void* data) {
                auto* saved = static_cast<Cache*>(data);
                saved->x.assign(xs, xs + saved->problem->dimension());
                return saved->problem->evaluate(saved->x, &saved->constraints);
            },
            &cache);
        opt.add_inequality_mconstraint(
            [](unsigned m, double* out, unsigned, const double* xs, double*, void* data) {
                auto* saved = static_cast<Cache*>(data);
                const std::vector<double> point(xs, xs + saved->problem->dimension());
                if (point != saved->x) {
                    saved->x = point;
                    saved->problem->evaluate(saved->x, &saved->constraints);
                }
                std::copy_n(saved->constraints.begin(), m, out);
            },
            &cache, std::vector<double>(problem.constraint_count(), 0.0));
        double value = 0.0;
        try {
            opt.optimize(x, value);
        } catch (const nlopt::roundoff_limited&) {
            // Ended by rounding: the best point visited is kept by the problem.
        } catch (const std::runtime_error& failure) {
            RFD_CHECK_MSG(false, failure.what());
        }
        progress.advance();
    }
    progress.finish();

    // The conditions at a design, and which of them hold the objective back.
    auto conditions_at = [&](const optics::Design& at, const Measures& m) {
        std::vector<Condition> conditions;
        for (std::size_t k : problem.checks()) {
            const auto& check = m.planes[k];
            const double tolerance = spec.tolerance_scale * check.tolerance;
            const double slack = tolerance - std::abs(check.plane_z - check.target_z);
            conditions.push_back({check.description + " (within " + format_fixed(tolerance, 3) + " mm)",
                                  std::isfinite(slack) ? slack : -1e300, slack < 0.02 * tolerance});
        }
        for (const auto& target : spec.targets) {
            const double v = m.value(target.measure);
            const double slack = target.at_least ? v - target.value : target.value - v;
            conditions.push_back({to_string(target), slack, slack < 0.01 * unit_of(target.measure)});
        }
        const std::vector<double> x = free_spacings(at, spec);
        for (std::size_t k = 0; k < n; ++k) {
            const std::size_t p = plane_index(design, spec.free[k].plane);
            // Writing z to 0.1 um may put parts that touch 0.1 um into each other: as
            // touching as the file can say.
            const double slack = std::min(x[k] - lower[k], upper[k] - x[k]) + kWrittenStep;
            conditions.push_back({"spacing " + design.planes[p - 1].name + "-" + design.planes[p].name +
                                      " within [" + format_fixed(lower[k], 4) + ", " + format_fixed(upper[k], 4) +
                                      "] mm",
                                  slack, slack < 0.01});
        }
        return conditions;
    };
    auto all_hold = [](const std::vector<Condition>& conditions) {
        return std::all_of(conditions.begin(), conditions.end(), [](const Condition& c) { return c.slack >= 0; });
    };

    // The file holds z to 0.1 um: the tuned design is the one the file will hold.
    optics::Design best = problem.at(problem.best_x());
    for (std::size_t k = 1; k < best.planes.size(); ++k) best.planes[k].z = as_written(best.planes[k].z);
    const Measures best_measures = measure(best);
    const auto best_conditions = conditions_at(best, best_measures);
    const bool best_holds = all_hold(best_conditions);
    result.given_was_feasible = all_hold(conditions_at(design, result.before));
    const bool better = best_measures.value(spec.maximise) > result.before.value(spec.maximise);
    const bool use_best = best_holds ? (better || !result.given_was_feasible) : !result.given_was_feasible;
    result.design = use_best ? best : design;
    result.after = use_best ? best_measures : result.before;
    result.conditions = use_best ? best_conditions : conditions_at(design, result.before);
    result.feasible = all_hold(result.conditions);
    result.spacing_after = free_spacings(result.design, spec);
    result.evaluations = problem.evaluations();
    return result;
}

std::string tuned_design_text(const std::string& original_text, const optics::Design& original,
                              const TuneResult& result, const std::string& header) {
    std::istringstream in(original_text);
    std::string out;
    std::istringstream header_in(header);
    for (std::string line; std::getline(header_in, line);) out += line.empty() ? "#\n" : "# " + line + "\n";
    out += "\n";
    std::string section;
    for (std::string line; std::getline(in, line);) {
        const std::size_t first = line.find_first_not_of(" \t");
        if (first != std::string::npos && line[first] == '[') {
            const std::size_t close = line.find(']', first);
            section = close == std::string::npos ? "" : line.substr(first + 1, close - first - 1);
        } else if (first != std::string::npos && section.rfind("planes.", 0) == 0 &&
                   line.compare(first, 4, "z_mm") == 0) {
            const std::string name = section.substr(7);
            const std::size_t k = plane_index(result.design, name);
            const std::size_t equals = line.find('=', first);
            if (k < result.design.planes.size() && equals != std::string::npos &&
                result.design.planes[k].z != original.planes[plane_index(original, name)].z) {
                const std::size_t comment = line.find('#', equals);
                line = line.substr(0, equals) + "= " + format_fixed(result.design.planes[k].z, 4) +
                       (comment == std::string::npos ? "" : "  " + line.substr(comment));
            }
        }
        out += line + "\n";
    }
    const optics::Design reread = optics::parse_design(out, original.file);
    for (std::size_t k = 0; k < reread.planes.size(); ++k)
        RFD_CHECK_MSG(std::abs(reread.planes[k].z - result.design.planes[k].z) < 0.5 * kWrittenStep,
                      "the tuned design file holds the tuned planes");
    return out;
}

}  // namespace rfd::tune
