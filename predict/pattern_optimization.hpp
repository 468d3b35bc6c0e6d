#pragma once
// `rfd pattern optimize` as library calls: a direct encoding in, the optimised pattern and
// the figures of its run out, the simulator's judgement of both patterns, and the report
// that charts them. The pieces are predict/optimize.hpp's; this is their use from a
// pattern file to a pattern file.
//
// Example:
//   PatternOptimization run = optimize_pattern(simulator, direct, reference.encoder(), settings);
//   write_optimized_pattern("optimized.exr", run, settings, direct.tone());
//   const auto judged = judge_patterns(simulator, direct, optimised, reference.encoder(), 9);
//   write_optimization_report("report", design.name, run, judged, false);

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "optics/display.hpp"
#include "optics/model.hpp"
#include "patterns/encode.hpp"
#include "predict/compare.hpp"
#include "predict/node_grid.hpp"
#include "predict/optimize.hpp"
#include "print/printed.hpp"

namespace rfd::predict {

/// What to optimise and how (the command's options; predict/optimize.hpp declares the
/// shared ones).
struct PatternOptimizationSettings {
    std::string from;             ///< the direct encoding's file: its attributes are kept
    std::string lights = "sweep"; ///< "sweep" (the nodes' directions) or a light file (.lp, field frame)
    double spacing_mm = kNodeSpacingOption.fallback;
    double stop_fraction = kStopFractionOption.fallback;
    double core_weight = kCoreWeightOption.fallback;
    int iterations = static_cast<int>(kIterationsOption.fallback);
    int rays_per_side = static_cast<int>(kOptimizeRaysOption.fallback);
    int chart_every = 5;          ///< held-out PSNR every this many iterations
    optics::ModelChoice model = optics::ModelChoice::Auto;
    std::optional<LensletWindow> crop;  ///< fit only these lenslets' cells
    std::string crop_text;        ///< as the user wrote it, for the pattern's attributes
    bool unbounded = false;       ///< CGLS without the printer's bounds: the ceiling
};

/// A run: the nodes found and what was measured on the way.
struct PatternOptimization {
    struct Point {
        int iteration = 0;
        double seconds = 0.0;      ///< the solver's time so far, without these evaluations
        double objective = 0.0;
        double fitted_psnr = 0.0;  ///< mean PSNR over the optimised directions (finite ones)
        double held_psnr = 0.0;    ///< the same over the held-out directions in between
    };
    NodeGrid nodes;
    std::vector<double> u;         ///< the solver's nodes (unbounded: not yet clamped)
    std::vector<Point> points;     ///< at 0, every chart_every iterations, and at the end
    optics::Model model = optics::Model::Paraxial;
    std::size_t directions = 0, held_out_directions = 0;
    int iterations = 0;
    bool converged = false;
    double prepare_seconds = 0.0, solve_seconds = 0.0;
};

/// Optimises `direct` (printed as the command reads it; `encoder` built from its field
/// with its options) through `simulator`. InputError when a light file has no light inside
/// the field of view or no node lies inside a cell; Error when the solver yields NaN.
PatternOptimization optimize_pattern(const optics::DisplaySimulator& simulator, const print::PrintedTransparency& direct,
                                     const patterns::Encoder& encoder, const PatternOptimizationSettings& settings);

/// Writes the optimised pattern: the direct encoding's attributes and the optimiser's
/// settings (optimized, optimized_from, ...); unbounded nodes clamped to print.
void write_optimized_pattern(const std::filesystem::path& file, const PatternOptimization& run,
                             const PatternOptimizationSettings& settings, const print::ToneMap& tone);

/// The simulator's judgement of one light direction, as `simulate compare` measures it:
/// exact model, every pattern as printed, each PSNR against the field's brightest value over
/// the sweep (psnr_against_field_db; 0 where the field is black everywhere).
struct JudgedDirection {
    double display_angle_deg = 0.0;
    bool inside_field_of_view = false, crosstalk_free = false;
    double direct_psnr_db = 0.0, optimized_psnr_db = 0.0;            ///< per lenslet (cores)
    double direct_cell_psnr_db = 0.0, optimized_cell_psnr_db = 0.0;  ///< over whole cells
    bool cores = false;  ///< the per-lenslet figures are over macro-pixel cores (Design II)
};
/// One direction from the two patterns' comparisons against the same reference, with the
/// one PSNR of `simulate compare` and the verdict: against `field_peak`, so that where the
/// field is dark a faint residue does not read as a failure.
JudgedDirection judge_direction(const DirectionComparison& direct, const DirectionComparison& optimized,
                                double field_peak);
std::vector<JudgedDirection> judge_patterns(const optics::DisplaySimulator& simulator,
                                            const print::PrintedTransparency& direct,
                                            const print::PrintedTransparency& optimized,
                                            const patterns::Encoder& encoder, int count);

/// Means of the judgement: inside the field of view (per lenslet) and in the crosstalk-free
/// cone (whole cells); NaN where no direction counts.
struct JudgedMeans {
    double in_fov_direct_db = 0.0, in_fov_optimized_db = 0.0;
    int in_fov_count = 0;
    double clean_cells_direct_db = 0.0, clean_cells_optimized_db = 0.0;
    int clean_cells_count = 0;
};
JudgedMeans judged_means(const std::vector<JudgedDirection>& judged);

/// The report folder: iterations.csv and convergence.{csv,gp,svg,png} (against iterations,
/// or with `timings` the solver's seconds), and when judged, directions.csv and
/// compare.{csv,gp,svg,png}.
void write_optimization_report(const std::filesystem::path& folder, const std::string& design_name,
                               const PatternOptimization& run, const std::vector<JudgedDirection>& judged,
                               bool timings);

/// The run for `--json` and as text (what the command prints).
nlohmann::json optimization_json(const PatternOptimization& run, const PatternOptimizationSettings& settings,
                                 const std::string& out, const std::vector<JudgedDirection>& judged);
std::string optimization_text(const PatternOptimization& run, const PatternOptimizationSettings& settings,
                              const std::string& out, const std::vector<JudgedDirection>& judged);

}  // namespace rfd::predict
