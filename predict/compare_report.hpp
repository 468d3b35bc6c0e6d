#pragma once
// `rfd simulate compare` as library calls: the prediction against the relit field over a
// sweep of light directions (predict/compare.hpp), optionally the simulator's speed against
// its accuracy, and the folder that reports them (docs/usage.md, "Prediction against
// relighting"; summary.json is predict/summaries.hpp's CompareSummary).
//
// Example:
//   ComparisonRun run = run_comparison(simulator, pattern, comparison, settings);
//   run.summary.design = design.name;  // who and what: the caller's
//   write_comparison_report("cmp", run, design.name, {});

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "optics/display.hpp"
#include "predict/compare.hpp"
#include "predict/summaries.hpp"
#include "print/printed.hpp"

namespace rfd::predict {

struct ComparisonSettings {
    optics::SimulationOptions options;      ///< the prediction's model, rays and pixels
    int sweep = 0;                          ///< directions over the display's range (DisplayComparison::sweep)
    std::vector<Eigen::Vector3d> lights;    ///< then these field directions (toward the light)
    /// Speed against accuracy: each model at each ray count against the exact model at
    /// `reference_rays`; none when `accuracy_models` is empty.
    std::vector<AccuracyModel> accuracy_models;
    std::vector<int> accuracy_rays;
    int reference_rays = 32;
};

struct ComparisonRun {
    std::vector<DirectionComparison> results;  ///< the sweep's directions, then the lights'
    /// Every figure; design, pattern, field, model names and the lattice for the caller.
    CompareSummary summary;
    std::vector<AccuracyPoint> accuracy;
};

/// Compares every direction, then (when asked) charts speed against accuracy over those
/// inside the field of view (all when none is).
ComparisonRun run_comparison(const optics::DisplaySimulator& simulator, const print::PrintedTransparency& pattern,
                             const DisplayComparison& comparison, const ComparisonSettings& settings);

/// How the report's pictures look.
struct ComparisonPictures {
    int pixels_per_lenslet = 0;  ///< of the side-by-side PNGs; 0: about 240 pixels per panel
    double error_gain = 4.0;     ///< |error| times this in the error panel
};

/// OUT: per direction light_NN.png (prediction | reference | |error|) and its three EXRs,
/// contact_sheet.png, directions.csv, summary.json, psnr.{csv,gp,svg,png}; with accuracy
/// points, accuracy_points.csv and accuracy.{csv,gp,svg,png}. Charts last: without gnuplot
/// every number is on disk before the ToolError.
void write_comparison_report(const std::filesystem::path& folder, const ComparisonRun& run,
                             const ComparisonSettings& settings, const ComparisonPictures& pictures);

/// What `simulate compare` prints: a table of the directions and the means.
std::string comparison_text(const std::string& folder, const ComparisonRun& run, int reference_rays);

}  // namespace rfd::predict
