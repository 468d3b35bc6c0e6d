#pragma once
// The thesis's evaluation of sampling strategies, on a virtual light stage scene:
//  - fixed versus adaptive sampling (5.3, figures 5.4 and 5.5): near-uniform patterns of
//    several sizes and an adaptive run (initial pattern, m directions per iteration), each
//    relit at every direction of a dense narrow-kernel reference; the summed squared error
//    against the reference as a function of the image count;
//  - narrow versus wide kernels at a low image count (5.1, 5.4, figure 5.1): the same
//    pattern captured with the narrow and with the wide (prefiltering) light, both judged
//    against a dense wide-kernel reference, the signal that many images can represent
//    without aliasing. Undersampled narrow highlights and shadow edges interpolate into
//    ghosts that fade in and out between samples; the wide kernel's images do not.
//    The narrow dense reference's own distance to the prefiltered one is reported too: the
//    part of the narrow field's error that is sharpness, not aliasing.
// Errors are sums over reference directions of per-image sums of squared differences
// (evaluate.hpp), so counts of different patterns compare directly, as in figure 5.5.
//
// Example: StageCaptureDevice device(load_scene("scenes/bottle.toml"));
//          SamplingStudy study = run_sampling_study(device, SamplingStudyOptions{});

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "relight/adaptive.hpp"
#include "relight/field.hpp"
#include "relight/stage_device.hpp"

namespace rfd::relight {

struct SamplingStudyOptions {
    std::size_t reference_count = 4096;          ///< dense narrow reference (thesis: 10 000)
    std::vector<std::size_t> fixed_counts = {256, 384, 512, 640, 768, 896, 1025};
    std::size_t initial = 256;                   ///< adaptive: initial pattern
    AdaptiveOptions adaptive;                    ///< m = 16, up to 1024 images, 2 degrees
    std::size_t kernel_count = 256;              ///< n of the narrow/wide comparison
    std::size_t prefiltered_reference_count = 1025;  ///< dense wide-kernel reference
    std::uint64_t seed = 1;                      ///< of every repulsion pattern
    bool show_progress = true;
};

struct StudyPoint {
    std::size_t images = 0;
    double squared_error = 0.0;  ///< summed over the reference's directions
    double psnr = 0.0;           ///< dB, evaluate.hpp's peak convention
};

struct KernelComparison {
    std::size_t images = 0;
    double narrow_error = 0.0;     ///< narrow images vs the prefiltered reference
    double wide_error = 0.0;       ///< wide images vs the prefiltered reference
    double dense_narrow_error = 0.0;  ///< the narrow reference vs the prefiltered reference
    double narrow_psnr = 0.0, wide_psnr = 0.0, dense_narrow_psnr = 0.0;
};

struct SamplingStudy {
    std::vector<Eigen::Vector3d> reference_directions;
    std::vector<StudyPoint> fixed;        ///< one per fixed count, ascending
    std::vector<StudyPoint> adaptive;     ///< after the initial capture and each iteration
    std::vector<double> analysis_seconds; ///< adaptive analysis per iteration
    /// Fewest adaptive images whose error is at or below the largest fixed pattern's.
    std::optional<std::size_t> adaptive_images_to_match_largest_fixed;
    /// Per reference direction: errors of the largest fixed pattern and of the final
    /// adaptive field (figure 5.4).
    std::vector<double> largest_fixed_errors, final_adaptive_errors;
    KernelComparison kernels;
    ReflectanceField adaptive_field;      ///< the final adaptive field
    std::vector<std::size_t> adaptive_iteration;  ///< per image of it: 0 initial, then 1, 2...
    ReflectanceField narrow_sparse, wide_sparse;  ///< the kernel comparison's fields
};

SamplingStudy run_sampling_study(StageCaptureDevice& device, const SamplingStudyOptions& options);

}  // namespace rfd::relight
