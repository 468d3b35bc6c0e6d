#include "relight/sampling_study.hpp"

#include <algorithm>
#include <string>

#include "core/error.hpp"
#include "core/progress.hpp"
#include "relight/evaluate.hpp"
#include "relight/interpolation.hpp"
#include "relight/sampling.hpp"

namespace rfd::relight {
namespace {

// Captures in batches so a progress bar can move during thousands of renders.
ReflectanceField capture_field(StageCaptureDevice& device, const std::vector<Eigen::Vector3d>& directions,
                               KernelChoice choice, const std::string& label, bool show_progress) {
    constexpr std::size_t kBatch = 32;
    ReflectanceField field;
    field.directions = directions;
    field.images.reserve(directions.size());
    std::optional<Progress> progress;
    if (show_progress) progress.emplace(label, directions.size());
    for (std::size_t begin = 0; begin < directions.size(); begin += kBatch) {
        const std::size_t end = std::min(begin + kBatch, directions.size());
        const std::vector<Eigen::Vector3d> batch(directions.begin() + static_cast<std::ptrdiff_t>(begin),
                                                 directions.begin() + static_cast<std::ptrdiff_t>(end));
        for (Image& image : device.capture(batch, choice)) field.images.push_back(std::move(image));
        if (progress) progress->advance(end - begin);
    }
    if (progress) progress->finish();
    field.kernel_radii.assign(directions.size(), device.kernel_radius(choice));
    return field;
}

StudyPoint point_of(std::size_t images, const Evaluation& evaluation) {
    return {images, evaluation.total_squared_error, evaluation.psnr};
}

}  // namespace

SamplingStudy run_sampling_study(StageCaptureDevice& device, const SamplingStudyOptions& options) {
    RFD_CHECK(!options.fixed_counts.empty() && options.initial >= 3);
    SamplingStudy study;
    // Distinct seeds: a reference sharing directions with a tested pattern would reward it.
    const ReflectanceField reference =
        capture_field(device, repulsion_pattern(options.reference_count, options.seed + 1000),
                      KernelChoice::Narrow, "reference", options.show_progress);
    study.reference_directions = reference.directions;

    std::vector<std::size_t> counts = options.fixed_counts;
    std::sort(counts.begin(), counts.end());
    for (const std::size_t count : counts) {
        const ReflectanceField fixed = capture_field(device, repulsion_pattern(count, options.seed),
                                                     KernelChoice::Narrow,
                                                     "fixed " + std::to_string(count), options.show_progress);
        const Evaluation evaluation = evaluate(fixed, reference);
        study.fixed.push_back(point_of(count, evaluation));
        if (count == counts.back()) study.largest_fixed_errors = evaluation.per_direction;
        if (count == options.kernel_count) study.narrow_sparse = fixed;
    }

    {
        std::optional<Progress> progress;
        if (options.show_progress) progress.emplace("adaptive", options.adaptive.total);
        std::size_t shown = 0;
        std::vector<double> last_errors;
        const AdaptiveRun run = adaptive_capture(
            device, repulsion_pattern(options.initial, options.seed), delaunay_triangles, options.adaptive,
            [&](const AdaptiveRun& state) {
                const Evaluation evaluation = evaluate(state.field, reference);
                study.adaptive.push_back(point_of(state.field.size(), evaluation));
                last_errors = evaluation.per_direction;
                if (progress) progress->advance(state.field.size() - shown);
                shown = state.field.size();
            });
        if (progress) progress->finish();
        study.analysis_seconds = run.analysis_seconds;
        study.final_adaptive_errors = last_errors;
        study.adaptive_field = run.field;
        study.adaptive_iteration = run.iteration;
    }
    const double target = study.fixed.back().squared_error;
    for (const StudyPoint& point : study.adaptive)
        if (point.squared_error <= target) {
            study.adaptive_images_to_match_largest_fixed = point.images;
            break;
        }

    const std::vector<Eigen::Vector3d> kernel_pattern = repulsion_pattern(options.kernel_count, options.seed);
    if (study.narrow_sparse.size() != options.kernel_count)
        study.narrow_sparse = capture_field(device, kernel_pattern, KernelChoice::Narrow,
                                            "narrow " + std::to_string(options.kernel_count), options.show_progress);
    study.wide_sparse = capture_field(device, kernel_pattern, KernelChoice::Wide,
                                      "wide " + std::to_string(options.kernel_count), options.show_progress);
    const ReflectanceField prefiltered =
        capture_field(device, repulsion_pattern(options.prefiltered_reference_count, options.seed + 2000),
                      KernelChoice::Wide, "wide reference", options.show_progress);
    const Evaluation narrow = evaluate(study.narrow_sparse, prefiltered);
    const Evaluation wide = evaluate(study.wide_sparse, prefiltered);
    const Evaluation dense = evaluate(reference, prefiltered);
    study.kernels = {options.kernel_count, narrow.total_squared_error, wide.total_squared_error,
                     dense.total_squared_error, narrow.psnr, wide.psnr, dense.psnr};
    return study;
}

}  // namespace rfd::relight
