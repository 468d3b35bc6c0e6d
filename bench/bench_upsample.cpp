// Feature-guided upsampling (thesis chapter 6) at the size of the thesis's sphere scene,
// 453 x 211 RGB: one subdivision level of a 64-direction field of a plane with a floating
// occluder (moving shadows) and a glossy dome (a moving highlight). The counter
// ms_per_new_image is the whole run (semantics, flow, level sets, synthesis) over the images
// it adds; target under 1 s (the thesis: about 50 s per image without priors, 2006). With
// prior_iterations 0 and 3: the cost of the image-based priors (6.4.2).
// UpsampleLinearBaseline relights the inputs at the same new directions (relight::render,
// Delaunay blending): what a user gets without upsampling.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include <benchmark/benchmark.h>

#include "core/sphere.hpp"
#include "relight/render.hpp"
#include "relight/upsample.hpp"

namespace rfd::relight {
namespace {

constexpr int kWidth = 453, kHeight = 211;

float shade(int x, int y, const Eigen::Vector3d& l) {
    const Eigen::Vector3d p(x - 0.5 * kWidth, 0.5 * kHeight - y, 0.0);
    const Eigen::Vector3d to_occluder = Eigen::Vector3d(-100.0, 0.0, 40.0) - p;
    const double along = to_occluder.dot(l);
    if (along > 0.0 && to_occluder.squaredNorm() - along * along < 25.0 * 25.0) return 0.01f;
    const Eigen::Vector3d d = p - Eigen::Vector3d(100.0, 0.0, 0.0);
    const double r = 60.0;
    if (d.x() * d.x() + d.y() * d.y() >= r * r) return static_cast<float>(0.5 * std::max(0.0, l.z()));
    const Eigen::Vector3d n = Eigen::Vector3d(d.x(), d.y(), std::sqrt(r * r - d.x() * d.x() - d.y() * d.y())) / r;
    const Eigen::Vector3d h = (l + Eigen::Vector3d::UnitZ()).normalized();
    return static_cast<float>(0.4 * std::max(0.0, n.dot(l)) + 5.0 * std::pow(std::max(0.0, n.dot(h)), 200.0));
}

const ReflectanceField& field() {
    static const ReflectanceField out = [] {
        ReflectanceField f;
        for (const auto& d : fibonacci_hemisphere(64)) {
            Image image(kWidth, kHeight, 3);
            for (int y = 0; y < kHeight; ++y)
                for (int x = 0; x < kWidth; ++x)
                    for (int c = 0; c < 3; ++c) image.at(x, y, c) = shade(x, y, d) * (0.6f + 0.2f * static_cast<float>(c));
            f.directions.push_back(d);
            f.images.push_back(std::move(image));
        }
        return f;
    }();
    return out;
}

// Argument: image-prior iterations (0: off, the fast-and-rough path; 3: the thesis's).
void UpsampleOneLevel(benchmark::State& state) {
    UpsampleOptions options;
    options.guard_tile = 0;  // the model's time; the guard adds its probes' (one each per probe)
    options.priors.iterations = static_cast<int>(state.range(0));
    std::size_t added = 0;
    double seconds = 0.0;
    for (auto _ : state) {
        const auto start = std::chrono::steady_clock::now();
        const UpsampledField up = upsample_field(field(), 1, options);
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        added += up.statistics.synthesized;
        benchmark::DoNotOptimize(up.field.images.back().samples().data());
    }
    state.counters["new_images"] = static_cast<double>(added) / static_cast<double>(state.iterations());
    state.counters["ms_per_new_image"] = 1e3 * seconds / static_cast<double>(added);
}
BENCHMARK(UpsampleOneLevel)->ArgName("prior_iterations")->Arg(0)->Arg(3)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

void UpsampleLinearBaseline(benchmark::State& state) {
    const ReflectanceField& f = field();
    UpsampleOptions unguarded;
    unguarded.guard_tile = 0;
    const UpsampledField up = upsample_field(f, 1, unguarded);
    for (auto _ : state)
        for (std::size_t k = f.size(); k < up.field.size(); ++k)
            benchmark::DoNotOptimize(render(f, {DirectionalLight{up.field.directions[k]}}).samples().data());
    state.counters["new_images"] = static_cast<double>(up.statistics.synthesized);
}
BENCHMARK(UpsampleLinearBaseline)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace rfd::relight
