// Repulsion patterns (thesis 5.2): time to relax n charges, each step an all-pairs pass over
// the charges and their mirror images. The study needs n = 4096 once per run; adaptive
// capture needs 256.

#include <benchmark/benchmark.h>

#include "relight/sampling.hpp"

namespace {

void BM_RepulsionPattern(benchmark::State& state) {
    const auto count = static_cast<std::size_t>(state.range(0));
    for (auto _ : state) benchmark::DoNotOptimize(rfd::relight::repulsion_pattern(count, 1));
}
BENCHMARK(BM_RepulsionPattern)->Arg(256)->Arg(1024)->Arg(4096)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
