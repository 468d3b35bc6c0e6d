// Dots per second of the Design IV pattern (patterns/angular.hpp) at the thesis's 2880 x
// 1440 dpi: rows through the middle of the 7 x 7 macro grid rendered one after another on
// one thread, for figure 8.15's diamonds (table field) and for a function field evaluated
// per bin sample (9 calls per dot). Baseline in the same run: filling the same row buffer
// (memory bandwidth), so results can be quoted as ratios. The optics tables are built once,
// outside the timed loop (their cost is reported by `rfd pattern encode-angular`).

#include <algorithm>
#include <span>
#include <vector>

#include <benchmark/benchmark.h>

#include "patterns/angular.hpp"

namespace rfd::patterns {
namespace {

const optics::DesignOptics& design4() {
    static const optics::DesignOptics optics(optics::load_design(std::string(RFD_SOURCE_DIR) + "/designs/design4.toml"));
    return optics;
}

void render_rows(benchmark::State& state, const AngularPattern& pattern) {
    const auto& g = pattern.geometry();
    std::vector<float> row(static_cast<std::size_t>(g.width) * static_cast<std::size_t>(pattern.channels()));
    int py = g.height / 2;
    for (auto _ : state) {
        pattern.render_row(py, row);
        benchmark::DoNotOptimize(row.data());
        py = py + 1 < g.height ? py + 1 : g.height / 2;
    }
    state.counters["dots/s"] = benchmark::Counter(static_cast<double>(state.iterations()) * g.width, benchmark::Counter::kIsRate);
}

void BM_DesignFourDiamonds(benchmark::State& state) {
    static const DiamondField field(0.25, 0.1);
    static const AngularPattern pattern(design4(), field, {});
    render_rows(state, pattern);
}
BENCHMARK(BM_DesignFourDiamonds)->Unit(benchmark::kMillisecond);

void BM_DesignFourFunction(benchmark::State& state) {
    static const FunctionField field(3, [](const Eigen::Vector3d& l, const Eigen::Vector3d& v, int u, int w, std::span<float> out) {
        out[0] = static_cast<float>(l.x() + v.x());
        out[1] = static_cast<float>(l.y() * v.y() + u);
        out[2] = static_cast<float>(v.z() + w);
    });
    static const AngularPattern pattern(design4(), field, {});
    render_rows(state, pattern);
}
BENCHMARK(BM_DesignFourFunction)->Unit(benchmark::kMillisecond);

void BM_RowFillBaseline(benchmark::State& state) {
    static const DiamondField field(0.25, 0.1);
    static const AngularPattern pattern(design4(), field, {});
    const auto& g = pattern.geometry();
    std::vector<float> row(static_cast<std::size_t>(g.width) * 3);
    float value = 0.0f;
    for (auto _ : state) {
        std::fill(row.begin(), row.end(), value);
        value += 1.0f;
        benchmark::DoNotOptimize(row.data());
    }
    state.counters["dots/s"] = benchmark::Counter(static_cast<double>(state.iterations()) * g.width, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RowFillBaseline)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rfd::patterns
