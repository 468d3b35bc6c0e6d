// The tolerance sweep (optics/tolerance.hpp) on Design I with 30 x 30 lenslets and a
// procedural checkerboard print (the sweep's cost, not a pattern file's), beside its
// baseline in the same run: one simulation of the three default lights. The sweep should
// cost its count of simulations, 3 x (1 + 4 kinds x 2 signs x (6 + 4)) = 243 of them, plus
// little: the ratio of the two figures says how much the decorator and comparison add.
// BM_MountedPattern shows the decorator's own overhead on one simulation.

#include <cmath>

#include <benchmark/benchmark.h>

#include "bench/checker.hpp"
#include "optics/display.hpp"
#include "optics/misalignment.hpp"
#include "optics/tolerance.hpp"

namespace {

using namespace rfd;

optics::Design design1_30x30() {
    return optics::with_lenslet_count(optics::load_design(std::string(RFD_SOURCE_DIR) + "/designs/design1.toml"), 30, 30);
}

using bench::Checker;

void BM_ToleranceBaselineOneSimulationPerLight(benchmark::State& state) {
    static const optics::Design design = design1_30x30();
    static const optics::DisplaySimulator simulator(design);
    const Checker checker;
    const auto lights = optics::default_tolerance_lights(simulator.optics(), optics::Model::Paraxial);
    for (auto _ : state)
        for (const auto& light : lights) {
            const optics::DiffuserImage image = simulator.simulate(checker, {light}, {});
            benchmark::DoNotOptimize(image.image.plane(0).data());
        }
}
BENCHMARK(BM_ToleranceBaselineOneSimulationPerLight)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ToleranceSweep(benchmark::State& state) {
    static const optics::Design design = design1_30x30();
    const optics::DisplaySimulator simulator(design);
    const Checker checker;
    const auto lights = optics::default_tolerance_lights(simulator.optics(), optics::Model::Paraxial);
    const optics::ToleranceOptions options = optics::default_tolerance_ranges(simulator.optics());
    for (auto _ : state) {
        const optics::ToleranceReport report = optics::sweep_tolerances(design, checker, lights, options);
        benchmark::DoNotOptimize(report.curves.data());
    }
}
BENCHMARK(BM_ToleranceSweep)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// One simulation through the decorator (a small turn) versus the bare pattern (arg 0).
void BM_MountedPattern(benchmark::State& state) {
    static const optics::Design design = design1_30x30();
    static const optics::DisplaySimulator simulator(design);
    const Checker checker;
    const optics::MisalignedTransparency mounted(checker, optics::Mounting{{0.01, 0.0}, 0.001, 1e-4});
    const optics::Transparency& pattern =
        state.range(0) == 0 ? static_cast<const optics::Transparency&>(checker) : mounted;
    const std::vector<optics::DisplayLight> light{{optics::incident_direction(0.1, 0.7), {1, 1, 1}, 0.0}};
    for (auto _ : state) {
        const optics::DiffuserImage image = simulator.simulate(pattern, light, {});
        benchmark::DoNotOptimize(image.image.plane(0).data());
    }
}
BENCHMARK(BM_MountedPattern)->Arg(0)->Arg(1)->ArgName("mounted")->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
