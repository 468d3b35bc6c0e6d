// The display simulator (optics/display.hpp) on Design I with 100 x 100 lenslets under one
// point light: paraxial (target <= 100 ms) and exact, in the same run so the exact model's
// cost is read as a ratio. The transparency is a procedural checkerboard of print dots, so
// the figure is the simulator's, not a pattern file's.

#include <cmath>
#include <fstream>
#include <sstream>

#include <benchmark/benchmark.h>

#include "core/parallel.hpp"
#include "core/sphere.hpp"
#include "optics/display.hpp"

namespace {

using namespace rfd;

optics::Design design1_100x100() {
    std::ifstream in(std::string(RFD_SOURCE_DIR) + "/designs/design1.toml");
    std::stringstream text;
    text << in.rdbuf();
    std::string design = text.str();
    const std::string preset = "count = [63, 73]";
    design.replace(design.find(preset), preset.size(), "count = [100, 100]");
    return optics::parse_design(design, "design1-100x100.toml");
}

// Alternate print dots (2880 x 1440 dpi) opaque and clear.
class Checker final : public optics::Transparency {
public:
    int channels() const override { return 1; }
    void sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const override {
        // In parallel, as RasterTransparency samples.
        parallel_for_chunks(points.size(), 1 << 14, [&](std::size_t begin, std::size_t end) {
            for (std::size_t k = begin; k < end; ++k) {
                const long x = std::lround(std::floor(points[k].x() / (25.4 / 2880)));
                const long y = std::lround(std::floor(points[k].y() / (25.4 / 1440)));
                out[k] = ((x + y) & 1) ? 1.0f : 0.25f;
            }
        });
    }
};

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
