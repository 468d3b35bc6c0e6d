// The virtual light stage: time to render one light of each bundled scene at its own
// resolution and sampling, after the light-independent camera paths are cached, for the
// narrow (2 degrees) and the wide (15 degrees) kernel; and the one-off cost of that cache.
// A sampling study renders thousands of lights per scene, so the per-light figure is what
// decides whether `rfd capture study` fits in a demo.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <string>

#include "core/progress.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/light_kernel.hpp"
#include "relight/scene.hpp"
#include "relight/stage.hpp"

namespace {

using namespace rfd::relight;

Scene bundled(const std::string& name) {
    rfd::Progress::set_quiet(true);
    return load_scene(std::string(RFD_SOURCE_DIR) + "/scenes/" + name + ".toml");
}

void render_lights(benchmark::State& state, const std::string& name, const LightKernel& kernel) {
    Scene scene = bundled(name);
    if (kernel.radius > scene.kernel.radius)
        scene.shadow_samples = std::max(scene.shadow_samples, default_shadow_samples(kernel));
    const LightStage stage(scene);
    // Lights walk down from the pole to near the horizon, where shadows are longest.
    int k = 0;
    for (auto _ : state) {
        const double theta = rfd::degrees_to_radians(5.0 + 80.0 * ((k * 37) % 100) / 100.0);
        const double phi = rfd::degrees_to_radians(137.5 * k);
        benchmark::DoNotOptimize(stage.render(rfd::direction_from_angles(theta, phi), kernel));
        ++k;
    }
    state.counters["pixels"] = static_cast<double>(stage.width() * stage.height());
}

void camera_paths(benchmark::State& state, const std::string& name) {
    const Scene scene = bundled(name);
    for (auto _ : state) benchmark::DoNotOptimize(LightStage(scene));
}

#define RFD_STAGE_BENCHMARKS(scene)                                                                  \
    BENCHMARK_CAPTURE(render_lights, scene##_narrow, #scene, LightKernel::narrow())                  \
        ->Unit(benchmark::kMillisecond)->UseRealTime();                                              \
    BENCHMARK_CAPTURE(render_lights, scene##_wide, #scene, LightKernel::wide())                      \
        ->Unit(benchmark::kMillisecond)->UseRealTime();                                              \
    BENCHMARK_CAPTURE(camera_paths, scene, #scene)->Unit(benchmark::kMillisecond)->UseRealTime();

RFD_STAGE_BENCHMARKS(spheres)
RFD_STAGE_BENCHMARKS(bottle)
RFD_STAGE_BENCHMARKS(figure)

}  // namespace
