// rfd relight upsample: feature-guided upsampling of a reflectance field (thesis chapter 6).

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "relight/field.hpp"
#include "relight/upsample.hpp"

namespace rfd::cli {

void add_upsample_command(CLI::App& relight) {
    auto* cmd = relight.add_subcommand(
        "upsample", "Synthesize images between a field's light directions: flowed highlights, moving shadows "
                    "(thesis chapter 6)");
    struct Options {
        std::string field, out, extension = ".exr";
        int levels = 1;
        relight::UpsampleOptions upsample;
        bool json = false;
        WindowOptions window;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("FIELD", opt->field, "Reflectance field (folder or .lp)")->required();
    add_window_options(*cmd, opt->window);
    cmd->add_option("--levels", opt->levels,
                    "Rounds of subdivision: each adds the midpoints of every Delaunay edge (about 3x the directions "
                    "so far); 1 or 2 are typical")
        ->capture_default_str();
    cmd->add_option("--out", opt->out, "Folder for the upsampled field: the inputs, then the new images")->required();
    relight::UpsampleOptions& u = opt->upsample;
    add_option(*cmd, relight::kHighlightFactorOption, u.f_highlight);
    add_option(*cmd, relight::kLitFractionOption, u.f_lit);
    add_option(*cmd, relight::kPercentileOption, u.percentile);
    add_option(*cmd, relight::kDilationOption, u.highlight_dilation);
    add_option(*cmd, relight::kBlurNeighboursOption, u.blur_neighbours);
    add_option(*cmd, relight::kFitNeighboursOption, u.fit_neighbours);
    add_option(*cmd, relight::kBlobReachOption, u.blob_reach);
    add_option(*cmd, relight::kLobeSamplesOption, u.lobe_samples);
    add_option(*cmd, relight::kLobeSpreadOption, u.lobe_spread_deg);
    add_option(*cmd, relight::kPriorIterationsOption, u.priors.iterations);
    add_option(*cmd, relight::kPriorProximityOption, u.priors.proximity);
    add_option(*cmd, relight::kGuardTileOption, u.guard_tile);
    add_option(*cmd, relight::kGuardProbesOption, u.guard_probes);
    // Checked before any work: a field is linear radiance, so only the float formats keep it.
    cmd->add_option("--format", opt->extension, "Image format of the output field: .exr or .hdr (linear float)")
        ->check(CLI::IsMember({".exr", ".hdr"}))
        ->capture_default_str();
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        const auto t0 = std::chrono::steady_clock::now();
        const relight::ReflectanceField field = relight::read_field(opt->field, opt->window.window());
        const auto t1 = std::chrono::steady_clock::now();
        const relight::UpsampledField up = relight::upsample_field(field, opt->levels, opt->upsample);
        const auto t2 = std::chrono::steady_clock::now();
        relight::write_field(opt->out, up.field, "field", opt->extension);
        const auto seconds = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
        const auto& s = up.statistics;
        const double per_image = s.synthesized > 0 ? seconds(t1, t2) / static_cast<double>(s.synthesized) : 0.0;
        if (opt->json) {
            const nlohmann::json summary = {{"field", opt->field},
                                            {"out", opt->out},
                                            {"levels", opt->levels},
                                            {"inputs", s.inputs},
                                            {"synthesized", s.synthesized},
                                            {"f_highlight", opt->upsample.f_highlight},
                                            {"f_lit", opt->upsample.f_lit},
                                            {"highlight_fraction", s.highlight_fraction},
                                            {"lit_fraction", s.lit_fraction},
                                            {"extrapolated_fraction", s.extrapolated_fraction},
                                            {"fallback_fraction", s.fallback_fraction},
                                            {"guard_probes", s.guard_probes},
                                            {"guarded_tiles", s.guarded_tiles},
                                            {"upsampled_tiles", s.upsampled_tiles},
                                            {"seconds_per_synthesized_image", per_image}};
            std::printf("%s\n", summary.dump(2).c_str());
            return;
        }
        std::printf("%s: %zu images -> %zu (%d level(s)), %d x %d\n", opt->field.c_str(), s.inputs,
                    s.inputs + s.synthesized, opt->levels, field.width(), field.height());
        std::printf("  highlight pixels     %.2f %% of input pixels (f_highlight %g)\n", 100.0 * s.highlight_fraction,
                    opt->upsample.f_highlight);
        std::printf("  lit pixels           %.2f %% of input pixels (f_lit %g)\n", 100.0 * s.lit_fraction,
                    opt->upsample.f_lit);
        std::printf("  extrapolated         %.2f %% of new pixels (spherical-harmonic fit)\n",
                    100.0 * s.extrapolated_fraction);
        std::printf("  no reliable samples  %.2f %% of new pixels (linear blend instead)\n",
                    100.0 * s.fallback_fraction);
        if (s.guard_probes > 0)
            std::printf("  guard                %zu of %zu tiles of %d px keep the upsampled images, the rest blended "
                        "(leave-one-out of %zu inputs)\n",
                        s.upsampled_tiles, s.guarded_tiles, opt->upsample.guard_tile, s.guard_probes);
        else if (opt->upsample.guard_tile > 0)
            std::printf("  guard                none: no input lies inside the others' triangulation to judge by\n");
        std::printf("  time                 %.2f s read, %.2f s upsampling (%.3f s per new image)\n", seconds(t0, t1),
                    seconds(t1, t2), per_image);
        std::printf("  wrote %s\n", opt->out.c_str());
    });
}

}  // namespace rfd::cli
