// Adaptive-sampling analysis (thesis 5.3): triangulation, one-rings, projection errors and
// insertion, per image of a run. The thesis needed about 1.9 s per image at 453x224; the
// target here is <= 20 ms.
//
// The run is the thesis's: 256 initial directions, 16 per iteration, up to 1024 images of
// 453x224 RGB. Images come from a synthetic device (a diffuse term plus a highlight whose
// position on the image moves with the light), generated outside the timed analysis. The
// reported time is AdaptiveRun::analysis_seconds summed over the run (what the thesis's
// 1.9 s covers); counter "ms/image" divides it by the final image count.

#include <benchmark/benchmark.h>

#include <cmath>
#include <numeric>
#include <vector>

#include "core/image.hpp"
#include "relight/adaptive.hpp"
#include "relight/interpolation.hpp"
#include "relight/sampling.hpp"

namespace {

using rfd::Image;
using namespace rfd::relight;

class MovingHighlightDevice : public CaptureDevice {
public:
    std::vector<Image> capture(const std::vector<Eigen::Vector3d>& directions, KernelChoice) override {
        std::vector<Image> images;
        for (const Eigen::Vector3d& d : directions) {
            Image image(kWidth, kHeight, 3);
            const double hx = (0.5 + 0.45 * d.x()) * kWidth, hy = (0.5 - 0.45 * d.y()) * kHeight;
            for (int c = 0; c < 3; ++c)
                for (int y = 0; y < kHeight; ++y)
                    for (int x = 0; x < kWidth; ++x) {
                        const double r2 = (x - hx) * (x - hx) + (y - hy) * (y - hy);
                        image.at(x, y, c) = static_cast<float>(0.3 * std::max(d.z(), 0.0) * (1 + 0.1 * c) +
                                                               std::exp(-r2 / 50.0));
                    }
            images.push_back(std::move(image));
        }
        return images;
    }
    double kernel_radius(KernelChoice) const override { return 0.0; }

private:
    static constexpr int kWidth = 453, kHeight = 224;
};

void BM_Adaptive_Analysis(benchmark::State& state) {
    AdaptiveOptions options;  // m = 16, 1024 images, 2 degrees
    const auto initial = repulsion_pattern(256, 1);
    double seconds = 0.0, images = 0.0;
    for (auto _ : state) {
        MovingHighlightDevice device;
        const AdaptiveRun run = adaptive_capture(device, initial, delaunay_triangles, options);
        const double analysis = std::accumulate(run.analysis_seconds.begin(), run.analysis_seconds.end(), 0.0);
        state.SetIterationTime(analysis);
        seconds += analysis;
        images += static_cast<double>(run.field.size());
    }
    state.counters["ms/image"] = 1e3 * seconds / images;
    state.counters["images"] = images / static_cast<double>(state.iterations());
}
BENCHMARK(BM_Adaptive_Analysis)->Unit(benchmark::kMillisecond)->UseManualTime()->Iterations(1);

}  // namespace
