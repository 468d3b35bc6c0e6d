#pragma once
// `rfd simulate tolerance`'s folder from a sweep of mounting errors
// (optics/tolerance.hpp): a chart per error kind, summary.txt and summary.json (the
// ToleranceSummary of predict/summaries.hpp that the verdict reads).
//
// Example:
//   const optics::ToleranceReport report = optics::sweep_tolerances(design, pattern, lights, options);
//   const auto written = write_tolerance_report("tolerance", report, {design.name, "p.exr", 30, "paraxial", 3});

#include <cstddef>
#include <filesystem>
#include <string>

#include "optics/tolerance.hpp"
#include "predict/summaries.hpp"

namespace rfd::predict {

/// Who and what the sweep was of, for the report's words.
struct ToleranceContext {
    std::string design;     ///< the design's name
    std::string pattern;    ///< the pattern file as the user named it
    double threshold_db = 30.0;
    std::string model;      ///< "paraxial" or "exact"
    std::size_t lights = 0;
};

/// What the report says: summary.json's record (its `summary` sentence says how far each
/// error may go) and summary.txt's text (a line per error kind, then that sentence).
struct ToleranceReportText {
    ToleranceSummary summary;
    std::string text;
};

/// Writes FOLDER/KIND.{csv,gp,svg,png} for every curve (PSNR, threshold, the tolerance found,
/// the picture's shift), summary.txt and summary.json. Charts before the summaries: a
/// missing gnuplot (ToolError) leaves no summary claiming charts that are not there.
ToleranceReportText write_tolerance_report(const std::filesystem::path& folder, const optics::ToleranceReport& report,
                                           const ToleranceContext& context);

}  // namespace rfd::predict
