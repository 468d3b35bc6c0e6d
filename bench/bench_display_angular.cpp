// The Design III/IV simulator (optics/display_angular.hpp): one point light, three distant
// views, paraxial against exact in the same run (the ratio is the figure to quote). Design
// IV's 49 macro-pixels share the traced rays, so its cost over Design III's is the pattern
// lookups and the binning, not the tracing.

#include <cmath>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "optics/display_angular.hpp"

namespace rfd {
namespace {

// A pattern of varying transmittance over the whole pattern plane.
class Stripes final : public optics::Transparency {
public:
    int channels() const override { return 1; }
    void sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const override {
        for (std::size_t k = 0; k < points.size(); ++k)
            out[k] = static_cast<float>(0.5 + 0.5 * std::sin(9.0 * points[k].x() + 4.0 * points[k].y()));
    }
};

void BM_SimulateAngular(benchmark::State& state) {
    const int design = static_cast<int>(state.range(0));
    static const optics::AngularDisplaySimulator design3(
        optics::load_design(std::string(RFD_SOURCE_DIR) + "/designs/design3.toml"));
    static const optics::AngularDisplaySimulator design4(
        optics::load_design(std::string(RFD_SOURCE_DIR) + "/designs/design4.toml"));
    const optics::AngularDisplaySimulator& simulator = design == 3 ? design3 : design4;
    optics::AngularSimulationOptions options;
    options.model = state.range(1) == 0 ? optics::Model::Paraxial : optics::Model::Exact;
    options.rays_per_side = 128;
    options.views = {{Eigen::Vector3d::UnitZ(), std::nullopt},
                     {Eigen::Vector3d(0.1, 0.0, 1.0).normalized(), std::nullopt},
                     {Eigen::Vector3d(0.0, -0.1, 1.0).normalized(), std::nullopt}};
    const std::vector<optics::DisplayLight> light{{optics::incident_direction(0.1, 0.7), {1, 1, 1}, 0.0}};
    const Stripes pattern;
    std::size_t rays = 0;
    for (auto _ : state) {
        const optics::AngularDisplayOutput out = simulator.simulate(pattern, light, options);
        rays = out.rays;
        benchmark::DoNotOptimize(out.views.front().plane(0).data());
    }
    state.SetLabel("Design " + std::string(design == 3 ? "III " : "IV ") + std::string(optics::to_string(options.model)));
    state.counters["rays"] = static_cast<double>(rays);
}
BENCHMARK(BM_SimulateAngular)
    ->Args({3, 0})
    ->Args({3, 1})
    ->Args({4, 0})
    ->Args({4, 1})
    ->ArgNames({"design", "exact"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace rfd
