#pragma once
// The `simulate` command's own options: read by its Designs I/II run
// (cli/simulate_commands.cpp) and its Designs III/IV run (cli/simulate_angular_commands.cpp).

#include <cstddef>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli/arguments.hpp"
#include "optics/display.hpp"
#include "optics/model.hpp"
#include "predict/display_lights.hpp"

namespace rfd::cli {

struct SimulateOptions {
    std::string design, pattern, out, lenslets, envmap;
    optics::ModelChoice model = optics::ModelChoice::Auto;
    PrintOptions print;
    std::vector<std::string> lights;
    predict::LightFrame frame = predict::kDefaultLightFrame;
    double tolerance_dots = optics::kModelToleranceOption.fallback, pixels_per_lenslet = 8.0, exposure = 0.0;
    int rays = static_cast<int>(optics::kRaysPerSideOption.fallback), area_samples = 5;
    std::size_t max_rays = 4096;
    std::vector<double> front{0.0, 0.1, 0.3, 1.0};
    optics::DiffuserScatter diffuser;
    bool json = false;
};

/// `simulate` for Designs III and IV: their own options, added to the `simulate` command,
/// and the run its callback hands over to (`simulate` is the command, for the checks of
/// which Designs I/II options were given).
struct ObserverVariantOptions;
std::shared_ptr<ObserverVariantOptions> add_observer_variant_options(CLI::App& simulate);
void simulate_observer_variant(const CLI::App& simulate, const SimulateOptions& common,
                               const ObserverVariantOptions& options);

}  // namespace rfd::cli
