// rfd capture study: the thesis's sampling evaluation (5.3-5.4, figures 5.4 and 5.5) on a
// virtual light stage scene: fixed versus adaptive sampling, narrow versus wide kernels.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/plot.hpp"
#include "core/text.hpp"
#include "core/units.hpp"
#include "relight/sampling_study.hpp"
#include "relight/scene.hpp"
#include "relight/stage_device.hpp"

namespace rfd::cli {
namespace {

struct StudyCommandOptions {
    std::string scene;
    std::string out;
    std::string resolution;
    int samples = 0;
    bool json = false;
    relight::SamplingStudyOptions study;
};

CsvTable study_csv(const relight::SamplingStudy& study) {
    CsvTable table({"strategy", "images", "squared_error", "psnr_db"});
    for (const auto& [strategy, points] : {std::pair{"fixed", &study.fixed}, std::pair{"adaptive", &study.adaptive}})
        for (const auto& p : *points)
            table.add_row({strategy, std::to_string(p.images), format_number(p.squared_error, 9), format_fixed(p.psnr, 4)});
    return table;
}

// Figure 5.5's analogue: summed squared error against the number of images taken.
LineChart error_chart(const relight::SamplingStudy& study, const std::string& scene_name) {
    LineChart chart;
    chart.title = "Relighting error vs. images, " + scene_name + " (reference: " +
                  std::to_string(study.reference_directions.size()) + " directions)";
    chart.x_label = "images n";
    chart.y_label = "summed squared error";
    chart.log_y = true;
    chart.key_position = "top right";  // the error falls from the top left
    PlotSeries fixed{"fixed (repulsion pattern)", {}, {}, false};
    for (const auto& p : study.fixed) {
        fixed.x.push_back(static_cast<double>(p.images));
        fixed.y.push_back(p.squared_error);
    }
    PlotSeries adaptive{"adaptive (m = 16)", {}, {}, false};
    for (const auto& p : study.adaptive) {
        adaptive.x.push_back(static_cast<double>(p.images));
        adaptive.y.push_back(p.squared_error);
    }
    chart.series = {fixed, adaptive};
    if (study.adaptive_images_to_match_largest_fixed)
        chart.vertical_markers.emplace_back(static_cast<double>(*study.adaptive_images_to_match_largest_fixed),
                                            "adaptive matches fixed " + std::to_string(study.fixed.back().images));
    return chart;
}

// Figure 5.4's analogue (error per reference direction, fixed and adaptive) and figure 5.3's
// (the adaptive directions, coloured by the iteration that added them).
void write_polar_maps(const relight::SamplingStudy& study, const std::filesystem::path& out) {
    const std::string fixed = std::to_string(study.fixed.back().images);
    const std::string adaptive = std::to_string(study.adaptive.back().images);
    write_polar_map({"Squared error per reference direction, fixed " + fixed + " images",
                     study.reference_directions, study.largest_fixed_errors, "squared error", true},
                    out / ("errors_fixed_" + fixed));
    write_polar_map({"Squared error per reference direction, adaptive " + adaptive + " images",
                     study.reference_directions, study.final_adaptive_errors, "squared error", true},
                    out / ("errors_adaptive_" + adaptive));
    std::vector<double> iteration;
    for (const std::size_t k : study.adaptive_iteration) iteration.push_back(static_cast<double>(k));
    write_polar_map({"Adaptive directions by iteration (0: initial pattern)", study.adaptive_field.directions,
                     iteration, "iteration", false},
                    out / "adaptive_directions");
}

nlohmann::json summary_of(const relight::SamplingStudy& study, const StudyCommandOptions& opt) {
    const auto& fixed_largest = study.fixed.back();
    const auto& adaptive_last = study.adaptive.back();
    const double analysis = std::accumulate(study.analysis_seconds.begin(), study.analysis_seconds.end(), 0.0);
    nlohmann::json summary = {
        {"scene", opt.scene},
        {"out", opt.out},
        {"reference_directions", study.reference_directions.size()},
        {"fixed_largest", {{"images", fixed_largest.images}, {"squared_error", fixed_largest.squared_error},
                           {"psnr_db", fixed_largest.psnr}}},
        {"adaptive_final", {{"images", adaptive_last.images}, {"squared_error", adaptive_last.squared_error},
                            {"psnr_db", adaptive_last.psnr}}},
        {"adaptive_images_to_match_largest_fixed", nullptr},
        {"adaptive_analysis_ms_per_image", 1e3 * analysis / static_cast<double>(adaptive_last.images)},
        {"kernels", {{"images", study.kernels.images},
                     {"narrow_error", study.kernels.narrow_error},
                     {"wide_error", study.kernels.wide_error},
                     {"dense_narrow_error", study.kernels.dense_narrow_error},
                     {"narrow_psnr_db", study.kernels.narrow_psnr},
                     {"wide_psnr_db", study.kernels.wide_psnr},
                     {"dense_narrow_psnr_db", study.kernels.dense_narrow_psnr}}}};
    if (study.adaptive_images_to_match_largest_fixed)
        summary["adaptive_images_to_match_largest_fixed"] = *study.adaptive_images_to_match_largest_fixed;
    return summary;
}

}  // namespace

void add_study_command(CLI::App& capture) {
    auto* cmd = capture.add_subcommand(
        "study", "Sampling study on a scene (thesis 5.3-5.4): fixed vs adaptive sampling, narrow vs wide kernels");
    auto opt = std::make_shared<StudyCommandOptions>();
    auto& s = opt->study;
    cmd->add_option("SCENE", opt->scene, "Scene TOML file for the virtual light stage")->required();
    cmd->add_option("--out", opt->out, "Output folder: study.csv, study.json, charts (docs/formats.md)")
        ->required();
    cmd->add_option("--resolution", opt->resolution, "Image size WxH (default: the scene's)");
    cmd->add_option("--samples-per-pixel", opt->samples, "Camera rays per pixel (default: the scene's)")
        ->check(CLI::Range(1, 4096));
    cmd->add_option("--reference", s.reference_count, "Directions of the dense narrow reference")
        ->check(CLI::Range(std::size_t{16}, std::size_t{100000}));
    cmd->add_option("--fixed", s.fixed_counts, "Sizes of the fixed patterns")
        ->delimiter(',')
        ->check(CLI::Range(std::size_t{3}, std::size_t{100000}));
    cmd->add_option("--initial", s.initial, "Adaptive: initial directions")
        ->check(CLI::Range(std::size_t{3}, std::size_t{100000}));
    cmd->add_option("--per-iteration", s.adaptive.per_iteration, "Adaptive: directions per iteration")
        ->check(CLI::Range(std::size_t{1}, std::size_t{100000}));
    cmd->add_option("--total", s.adaptive.total, "Adaptive: stop at this many images")
        ->check(CLI::Range(std::size_t{3}, std::size_t{1000000}));
    cmd->add_option("--kernel-count", s.kernel_count, "Images of the narrow/wide comparison")
        ->check(CLI::Range(std::size_t{3}, std::size_t{100000}));
    cmd->add_option("--wide-reference", s.prefiltered_reference_count,
                    "Directions of the dense wide-kernel reference")
        ->check(CLI::Range(std::size_t{16}, std::size_t{100000}));
    cmd->add_option("--seed", s.seed, "Seed of every sampling pattern");
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        const auto& options = opt->study;
        if (options.initial > options.adaptive.total)
            throw InputError("--total " + std::to_string(options.adaptive.total) + " is below --initial " +
                             std::to_string(options.initial));
        relight::Scene scene = relight::load_scene(opt->scene);
        apply_scene_overrides(scene, opt->resolution, opt->samples);
        relight::StageCaptureDevice device(scene);
        const relight::SamplingStudy study = relight::run_sampling_study(device, options);

        const std::filesystem::path out(opt->out);
        ensure_directory(out);
        study_csv(study).write(out / "study.csv");
        const nlohmann::json summary = summary_of(study, *opt);
        write_text_file(out / "study.json", summary.dump(2) + "\n");
        write_line_chart(error_chart(study, std::filesystem::path(opt->scene).stem().string()),
                         out / "error_vs_images");
        write_polar_maps(study, out);

        if (opt->json) {
            std::printf("%s\n", summary.dump(2).c_str());
            return;
        }
        const auto& fixed = study.fixed.back();
        const auto& adaptive = study.adaptive.back();
        std::printf("sampling study of %s against %zu reference directions, in %s\n", opt->scene.c_str(),
                    study.reference_directions.size(), opt->out.c_str());
        std::printf("  fixed %5zu images   error %.4g  PSNR %.2f dB\n", fixed.images, fixed.squared_error, fixed.psnr);
        std::printf("  adaptive %4zu images   error %.4g  PSNR %.2f dB\n", adaptive.images,
                    adaptive.squared_error, adaptive.psnr);
        if (study.adaptive_images_to_match_largest_fixed)
            std::printf("  adaptive reaches the fixed-%zu error with %zu images (%.0f%%)\n", fixed.images,
                        *study.adaptive_images_to_match_largest_fixed,
                        100.0 * static_cast<double>(*study.adaptive_images_to_match_largest_fixed) /
                            static_cast<double>(fixed.images));
        else
            std::printf("  adaptive does not reach the fixed-%zu error within %zu images\n", fixed.images,
                        adaptive.images);
        const auto& k = study.kernels;
        std::printf("  kernels at n = %zu vs the wide-kernel reference: narrow error %.4g (%.2f dB), "
                    "wide %.4g (%.2f dB), dense narrow %.4g\n",
                    k.images, k.narrow_error, k.narrow_psnr, k.wide_error, k.wide_psnr, k.dense_narrow_error);
        std::printf("  adaptive analysis  %.2f ms per image\n",
                    summary["adaptive_analysis_ms_per_image"].get<double>());
    });
}

}  // namespace rfd::cli
