// The display simulator (optics/display.hpp) on Design I with 100 x 100 lenslets under one
// point light: paraxial (target <= 100 ms) and exact, in the same run so the exact model's
// cost is read as a ratio. The transparency is a procedural checkerboard of print dots, so
// the figure is the simulator's, not a pattern file's.

#include <cmath>

#include <benchmark/benchmark.h>

#include "core/sphere.hpp"
#include "bench/checker.hpp"
#include "optics/display.hpp"

namespace {

using namespace rfd;

optics::Design design1_100x100() {
    return optics::with_lenslet_count(optics::load_design(std::string(RFD_SOURCE_DIR) + "/designs/design1.toml"), 100, 100);
}

using bench::Checker;

void BM_SimulatePointLight(benchmark::State& state) {
    static const optics::DisplaySimulator simulator(design1_100x100());
    const Checker checker;
    optics::SimulationOptions options;
    options.model = state.range(0) == 0 ? optics::Model::Paraxial : optics::Model::Exact;
    const std::vector<optics::DisplayLight> light{{optics::incident_direction(0.15, 0.7), {1, 1, 1}, 0.0}};
    std::size_t rays = 0;
    for (auto _ : state) {
        const optics::DiffuserImage image = simulator.simulate(checker, light, options);
        rays = image.rays;
        benchmark::DoNotOptimize(image.image.plane(0).data());
    }
    state.SetLabel(std::string(optics::to_string(options.model)));
    state.counters["rays"] = static_cast<double>(rays);
    state.counters["Mrays_per_s"] = benchmark::Counter(static_cast<double>(rays) / 1e6, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_SimulatePointLight)->Arg(0)->Arg(1)->ArgName("exact")->Unit(benchmark::kMillisecond)->UseRealTime();

// An environment map's worth of light: 1024 directions spread evenly over the back
// hemisphere (as a 64 x 32 latitude-longitude map lights it), paraxial, with the default
// ray budget (4096 rays per lenslet: 4 per direction). Target <= 2 s.
void BM_SimulateEnvironment(benchmark::State& state) {
    static const optics::DisplaySimulator simulator(design1_100x100());
    const Checker checker;
    optics::SimulationOptions options;
    options.model = optics::Model::Paraxial;
    std::vector<optics::DisplayLight> sky;
    for (const Eigen::Vector3d& d : fibonacci_hemisphere(static_cast<std::size_t>(state.range(0))))
        sky.push_back({d, {0.002, 0.002 * d.z(), 0.001}, 0.0});
    std::size_t rays = 0;
    for (auto _ : state) {
        const optics::DiffuserImage image = simulator.simulate(checker, sky, options);
        rays = image.rays;
        benchmark::DoNotOptimize(image.image.plane(0).data());
    }
    state.counters["directions"] = static_cast<double>(sky.size());
    state.counters["rays"] = static_cast<double>(rays);
    state.counters["Mrays_per_s"] = benchmark::Counter(static_cast<double>(rays) / 1e6, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_SimulateEnvironment)->Arg(1024)->ArgName("directions")->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
