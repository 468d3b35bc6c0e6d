// Implicit relighting (thesis 7.5) at the thesis's sizes: 272 training images, 64 x 64 RGB
// probes.
//  - ImplicitTrain: the PCA of 272 probes (per channel an SVD of 3 208 masked pixels x 272),
//    from probes already cut out; target under 2 s (the thesis: 20 s per channel, 2005).
//  - ImplicitPredict: MAP coefficients for one probe (both passes) and the combination of
//    272 training images of 453 x 211 RGB, the size of the thesis's upsampled scene; target
//    under 50 ms (the thesis: 2 s for the coefficients, 1-16 s per image). The combination
//    alone (relight() of the same images with the same coefficients) is measured beside it
//    as the baseline.

#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "core/sphere.hpp"
#include "relight/implicit.hpp"

namespace rfd::relight {
namespace {

constexpr std::size_t kTraining = 272;

// Deterministic training probes: a black ball under smooth random lights, plus noise.
const std::vector<Image>& probes() {
    static const std::vector<Image> out = [] {
        PhongMaterial ball;
        ball.exponent = 50.0;
        std::vector<Image> images;
        std::mt19937 rng(272);
        std::normal_distribution<double> noise(0.0, 1e-3);
        const auto centres = fibonacci_hemisphere(kTraining);
        for (const auto& c : centres) {
            Image probe = render_probe({DiskLight{c, 0.4, Eigen::Vector3d::Ones()}}, ball, kProbeSize);
            for (float& s : probe.samples()) s = static_cast<float>(s + noise(rng));
            images.push_back(crop_probe(probe, {0.0, 0.0, double(kProbeSize), double(kProbeSize)}));
        }
        return images;
    }();
    return out;
}

const std::vector<Image>& scenes() {
    static const std::vector<Image> out = [] {
        std::vector<Image> images;
        std::mt19937 rng(453);
        std::uniform_real_distribution<float> value(0.0f, 1.0f);
        for (std::size_t i = 0; i < kTraining; ++i) {
            Image image(453, 211, 3);
            for (float& s : image.samples()) s = value(rng);
            images.push_back(std::move(image));
        }
        return images;
    }();
    return out;
}

void ImplicitTrain(benchmark::State& state) {
    const auto& training = probes();
    for (auto _ : state) benchmark::DoNotOptimize(train_implicit(training));
    state.counters["images"] = static_cast<double>(training.size());
}
BENCHMARK(ImplicitTrain)->Unit(benchmark::kMillisecond)->UseRealTime();

void ImplicitPredict(benchmark::State& state) {
    const ImplicitModel model = train_implicit(probes());
    const auto& images = scenes();
    const Image probe = probes()[100];
    for (auto _ : state) {
        const ImplicitFit fit = implicit_fit(model, probe, {.eta = 1e-6});
        benchmark::DoNotOptimize(relight(images, fit.coefficients()));
    }
}
BENCHMARK(ImplicitPredict)->Unit(benchmark::kMillisecond)->UseRealTime();

void ImplicitCombineOnly(benchmark::State& state) {
    const ImplicitModel model = train_implicit(probes());
    const auto& images = scenes();
    const LightCoefficients k = implicit_fit(model, probes()[100], {.eta = 1e-6}).coefficients();
    for (auto _ : state) benchmark::DoNotOptimize(relight(images, k));
}
BENCHMARK(ImplicitCombineOnly)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace rfd::relight
