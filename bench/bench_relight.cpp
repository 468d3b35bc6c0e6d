// Spherical interpolation and relighting throughput.
//  - weights/s of the Delaunay and the nearest-neighbour interpolation over 1024 directions
//    (queries spread over the upper hemisphere);
//  - relighting n = 1024 images of 512 x 512 RGB float (3 GiB) with every coefficient
//    non-zero, in bytes of field read per second and as a fraction of a plain streaming read
//    of the same images measured in the same process (the memory-bandwidth baseline): the
//    relighting pass is memory bound, so that fraction is its efficiency.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>

#include <benchmark/benchmark.h>

#include "core/parallel.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/interpolation.hpp"
#include "relight/render.hpp"

namespace rfd::relight {
namespace {

std::vector<Eigen::Vector3d> random_queries(std::size_t count) {
    std::mt19937_64 random(2026);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<Eigen::Vector3d> out;
    for (std::size_t i = 0; i < count; ++i) {
        const double z = unit(random), phi = 2.0 * kPi * unit(random), r = std::sqrt(1.0 - z * z);
        out.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
    }
    return out;
}

void weights_benchmark(benchmark::State& state, Interpolation method) {
    const SphericalInterpolator interp(fibonacci_hemisphere(static_cast<std::size_t>(state.range(0))));
    const auto queries = random_queries(1 << 16);
    for (auto _ : state) {
        double sum = 0.0;
        for (const auto& q : queries) sum += interp.weights(q, method).weight[0];
        benchmark::DoNotOptimize(sum);
    }
    state.counters["weights/s"] = benchmark::Counter(
        static_cast<double>(state.iterations()) * static_cast<double>(queries.size()), benchmark::Counter::kIsRate);
}

void BM_WeightsDelaunay(benchmark::State& state) { weights_benchmark(state, Interpolation::Delaunay); }
void BM_WeightsNearest(benchmark::State& state) { weights_benchmark(state, Interpolation::Nearest); }
BENCHMARK(BM_WeightsDelaunay)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_WeightsNearest)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond);

void BM_Triangulate(benchmark::State& state) {
    const auto directions = fibonacci_hemisphere(static_cast<std::size_t>(state.range(0)));
    for (auto _ : state) benchmark::DoNotOptimize(SphericalInterpolator(directions).triangles().size());
}
BENCHMARK(BM_Triangulate)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond);

constexpr std::size_t kImages = 1024;  // the size: 3 GiB of field
constexpr int kSide = 512;

const ReflectanceField& big_field() {
    static const ReflectanceField field = [] {
        ReflectanceField f;
        f.directions = fibonacci_hemisphere(kImages);
        for (std::size_t i = 0; i < kImages; ++i) {
            Image image(kSide, kSide, 3);
            auto samples = image.samples();
            for (std::size_t k = 0; k < samples.size(); ++k)
                samples[k] = static_cast<float>((k * 7 + i * 13) % 1024) / 1024.0f;
            f.images.push_back(std::move(image));
        }
        return f;
    }();
    return field;
}

double field_bytes() {
    return static_cast<double>(kImages) * kSide * kSide * 3 * sizeof(float);
}

// The baseline: every plane of every image summed, planes in parallel, vectorisable lanes.
double stream_read(const ReflectanceField& field) {
    std::vector<float> sums(field.size() * 3);
    parallel_for_chunks(sums.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t p = begin; p < end; ++p) {
            const auto plane = field.images[p / 3].plane(static_cast<int>(p % 3));
            std::array<float, 16> lanes{};
            for (std::size_t k = 0; k + 16 <= plane.size(); k += 16)
                for (std::size_t l = 0; l < 16; ++l) lanes[l] += plane[k + l];
            float s = 0.0f;
            for (const float v : lanes) s += v;
            sums[p] = s;
        }
    });
    float total = 0.0f;
    for (const float s : sums) total += s;
    return total;
}

double baseline_bytes_per_second() {
    static const double rate = [] {
        const ReflectanceField& field = big_field();
        double best = 0.0;
        for (int run = 0; run < 5; ++run) {
            const auto t0 = std::chrono::steady_clock::now();
            benchmark::DoNotOptimize(stream_read(field));
            const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            best = std::max(best, field_bytes() / seconds);
        }
        return best;
    }();
    return rate;
}

void BM_StreamingReadBaseline(benchmark::State& state) {
    const ReflectanceField& field = big_field();
    for (auto _ : state) benchmark::DoNotOptimize(stream_read(field));
    state.counters["bytes/s"] = benchmark::Counter(static_cast<double>(state.iterations()) * field_bytes(),
                                                   benchmark::Counter::kIsRate);
}
BENCHMARK(BM_StreamingReadBaseline)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Relight(benchmark::State& state) {
    const ReflectanceField& field = big_field();
    LightCoefficients k;
    k.k.resize(static_cast<Eigen::Index>(kImages), 3);
    for (Eigen::Index i = 0; i < k.k.rows(); ++i)
        k.k.row(i) = Eigen::RowVector3d(1.0, 0.9, 0.8) * (1.0 + static_cast<double>(i)) / static_cast<double>(kImages);
    k.nonzero = kImages;
    k.grey = false;
    const double baseline = baseline_bytes_per_second();
    const auto t0 = std::chrono::steady_clock::now();
    for (auto _ : state) benchmark::DoNotOptimize(relight(field, k).samples().data());
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double rate = static_cast<double>(state.iterations()) * field_bytes() / seconds;
    state.counters["bytes/s"] = rate;
    state.counters["baseline_bytes/s"] = baseline;
    state.counters["of_bandwidth"] = rate / baseline;
}
BENCHMARK(BM_Relight)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace rfd::relight
