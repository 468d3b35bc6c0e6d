// Rays per second of the paraxial and the exact engine on a 100 x 100 lenslet array
// (a Design-I-like hexagonal array: curved front, flat back, pattern plane at focus).
// Counters: rays/s and ray-surface interactions/s (3 surfaces per ray). A memory-streaming
// baseline over the same arrays runs in the same process so results can be quoted as
// ratios, which travel between machines better than absolute times.
// The paraxial batch runs stage by stage over blocks of rays with branch-free masks; on
// AVX2 machines a clone compiled for them is picked at load time (same bits either way).
// The paraxial engine folds surfaces that test nothing (here the array's flat back) into
// the transfer matrix of the next one; they still count as interactions, since the
// composed matrix computes their effect exactly.

#include <random>

#include <benchmark/benchmark.h>

#include "core/parallel.hpp"
#include "optics/exact.hpp"
#include "optics/paraxial.hpp"

namespace rfd::optics {
namespace {

constexpr std::size_t kRays = 1 << 20;
constexpr double kSurfaces = 3.0;

SequentialSystem lenslet_array_system() {
    const Lattice lattice = Lattice::hexagonal(2.358, 100, 100);
    SequentialSystem system;
    system.name = "100 x 100 hexagonal lenslet array";
    system.surfaces.push_back({Conic{1.0 / 1.4751, 0.0}, LatticeAperture{lattice}, 0.0, 1.4917, "front"});
    system.surfaces.push_back({Flat{}, Unbounded{}, 2.0, 1.0, "back"});
    const double focus = cardinal_points(system, 0, 1).rear_focal_z;
    system.surfaces.push_back({Flat{}, LatticeAperture{lattice}, focus, 1.0, "pattern"});
    return system;
}

const SequentialSystem& shared_system() {
    static const SequentialSystem system = lenslet_array_system();
    return system;
}

// Rays spread over the whole array, within +-10 degrees, from a plane 1 mm in front.
template <typename Set>
void fill_rays(Set set) {
    std::mt19937_64 random(2026);
    std::uniform_real_distribution<double> x(-115.0, 115.0), y(-100.0, 100.0), slope(-0.176, 0.176);
    for (std::size_t k = 0; k < kRays; ++k) set(k, x(random), y(random), slope(random), slope(random));
}

void set_counters(benchmark::State& state) {
    const double rays = static_cast<double>(state.iterations()) * static_cast<double>(kRays);
    state.counters["rays/s"] = benchmark::Counter(rays, benchmark::Counter::kIsRate);
    state.counters["ray-surface/s"] = benchmark::Counter(rays * kSurfaces, benchmark::Counter::kIsRate);
}

RayBatch exact_rays() {
    RayBatch batch;
    batch.resize(kRays);
    fill_rays([&](std::size_t k, double x, double y, double tx, double ty) {
        batch.set(k, Ray{Eigen::Vector3d(x, y, -1.0), Eigen::Vector3d(tx, ty, 1.0).normalized()});
    });
    return batch;
}

ParaxialBatch paraxial_rays() {
    ParaxialBatch batch;
    batch.resize(kRays);
    fill_rays([&](std::size_t k, double x, double y, double tx, double ty) {
        batch.x[k] = x;
        batch.y[k] = y;
        batch.tx[k] = tx;
        batch.ty[k] = ty;
    });
    return batch;
}

// Baseline: stream the paraxial arrays once per surface doing a free-space transfer, all
// cores. What any tracer over these arrays costs at the least.
void BM_Baseline_StreamTransfer(benchmark::State& state) {
    const ParaxialBatch start = paraxial_rays();
    ParaxialBatch batch = start;
    for (auto _ : state) {
        parallel_for_chunks(kRays, 4096, [&](std::size_t begin, std::size_t end) {
            for (int s = 0; s < 3; ++s)
                for (std::size_t k = begin; k < end; ++k) {
                    batch.x[k] += 0.5 * batch.tx[k];
                    batch.y[k] += 0.5 * batch.ty[k];
                }
        });
        benchmark::DoNotOptimize(batch.x.data());
    }
    set_counters(state);
}
BENCHMARK(BM_Baseline_StreamTransfer)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Paraxial_Batch(benchmark::State& state) {
    const SequentialSystem& system = shared_system();
    const ParaxialBatch start = paraxial_rays();
    ParaxialBatch batch;
    for (auto _ : state) {
        state.PauseTiming();
        batch = start;
        state.ResumeTiming();
        trace_paraxial_batch(system, batch, -1.0, 0, 2);
        benchmark::DoNotOptimize(batch.x.data());
    }
    set_counters(state);
}
BENCHMARK(BM_Paraxial_Batch)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Paraxial_SingleThread(benchmark::State& state) {
    const SequentialSystem& system = shared_system();
    const ParaxialBatch start = paraxial_rays();
    for (auto _ : state) {
        double sum = 0.0;
        for (std::size_t k = 0; k < kRays; ++k) {
            const auto r = trace_paraxial(system, {start.x[k], start.y[k], start.tx[k], start.ty[k]}, -1.0, 0, 2);
            sum += r.ray.x;
        }
        benchmark::DoNotOptimize(sum);
    }
    set_counters(state);
}
BENCHMARK(BM_Paraxial_SingleThread)->Unit(benchmark::kMillisecond);

void BM_Exact_Batch(benchmark::State& state) {
    const SequentialSystem& system = shared_system();
    const RayBatch start = exact_rays();
    RayBatch batch;
    for (auto _ : state) {
        state.PauseTiming();
        batch = start;
        state.ResumeTiming();
        trace_batch(system, batch, 0, 2);
        benchmark::DoNotOptimize(batch.x.data());
    }
    set_counters(state);
}
BENCHMARK(BM_Exact_Batch)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Exact_SingleThread(benchmark::State& state) {
    const SequentialSystem& system = shared_system();
    const RayBatch start = exact_rays();
    for (auto _ : state) {
        double sum = 0.0;
        for (std::size_t k = 0; k < kRays; ++k) sum += trace(system, start.get(k), 0, 2).ray.origin.x();
        benchmark::DoNotOptimize(sum);
    }
    set_counters(state);
}
BENCHMARK(BM_Exact_SingleThread)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rfd::optics
