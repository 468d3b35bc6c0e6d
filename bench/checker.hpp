#pragma once
// A transparency for the display benchmarks: alternate print dots (2880 x 1440 dpi) clear
// and at 0.25, computed rather than read, so the figures are the simulator's and not a
// pattern file's. Sampled in parallel, as RasterTransparency samples.

#include <cmath>
#include <span>

#include "core/parallel.hpp"
#include "optics/display.hpp"

namespace rfd::bench {

class Checker final : public optics::Transparency {
public:
    int channels() const override { return 1; }
    void sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const override {
        parallel_for_chunks(points.size(), 1 << 14, [&](std::size_t begin, std::size_t end) {
            for (std::size_t k = begin; k < end; ++k) {
                const long x = std::lround(std::floor(points[k].x() / (25.4 / 2880)));
                const long y = std::lround(std::floor(points[k].y() / (25.4 / 1440)));
                out[k] = ((x + y) & 1) ? 1.0f : 0.25f;
            }
        });
    }
};

}  // namespace rfd::bench
