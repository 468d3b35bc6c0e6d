#include "core/resample.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace rfd {

AxisResampling::AxisResampling(int from, int to) : from_(from), to_(to) {
    RFD_CHECK(from > 0 && to > 0);
    first_.reserve(static_cast<std::size_t>(to));
    offset_.reserve(static_cast<std::size_t>(to) + 1);
    offset_.push_back(0);
    const double step = static_cast<double>(from) / to;  // source pixels per output pixel
    for (int o = 0; o < to; ++o) {
        if (step >= 1.0) {
            // The source interval [o, o + 1) * step, each pixel weighted by its overlap.
            const double begin = o * step, end = std::min((o + 1) * step, static_cast<double>(from));
            const int s0 = static_cast<int>(std::floor(begin));
            const int s1 = std::min(from, static_cast<int>(std::ceil(end)));
            first_.push_back(s0);
            for (int s = s0; s < s1; ++s) {
                const double overlap = std::min(end, s + 1.0) - std::max(begin, static_cast<double>(s));
                weights_.push_back(static_cast<float>(overlap / step));
            }
        } else {
            // Linear between the two source pixels nearest the output pixel's centre.
            const double at = (o + 0.5) * step - 0.5;
            int s = static_cast<int>(std::floor(at));
            double f = at - s;
            if (s < 0 || s >= from - 1) {
                s = std::clamp(s, 0, from - 1);
                f = 0.0;
            }
            first_.push_back(s);
            weights_.push_back(static_cast<float>(1.0 - f));
            if (f > 0.0) weights_.push_back(static_cast<float>(f));
        }
        offset_.push_back(weights_.size());
    }
}

Image resample_band(const Image& source, int source_y0, const AxisResampling& columns, const AxisResampling& rows,
                    int y0, int y1) {
    RFD_CHECK(0 <= y0 && y0 < y1 && y1 <= rows.to() && source.width() == columns.from());
    const int first_row = rows.first(y0), end_row = rows.end(y1 - 1);
    RFD_CHECK(source_y0 <= first_row && end_row <= source_y0 + source.height());
    const int width = columns.to(), channels = source.channels();
    // Across first, on the source rows the band reads; then down.
    Image across(width, end_row - first_row, channels);
    for (int c = 0; c < channels; ++c)
        for (int y = first_row; y < end_row; ++y) {
            const float* in = source.plane(c).data() + static_cast<std::size_t>(y - source_y0) * source.width();
            float* out = across.plane(c).data() + static_cast<std::size_t>(y - first_row) * width;
            for (int x = 0; x < width; ++x) {
                const float* w = columns.weights(x);
                const int s0 = columns.first(x), taps = columns.end(x) - s0;
                float sum = 0.0f;
                for (int t = 0; t < taps; ++t) sum += w[t] * in[s0 + t];
                out[x] = sum;
            }
        }
    Image band(width, y1 - y0, channels);
    for (int c = 0; c < channels; ++c)
        for (int y = y0; y < y1; ++y) {
            float* out = band.plane(c).data() + static_cast<std::size_t>(y - y0) * width;
            const float* w = rows.weights(y);
            const int s0 = rows.first(y), taps = rows.end(y) - s0;
            for (int t = 0; t < taps; ++t) {
                const float* in = across.plane(c).data() + static_cast<std::size_t>(s0 + t - first_row) * width;
                const float weight = w[t];
                for (int x = 0; x < width; ++x) out[x] += weight * in[x];
            }
        }
    return band;
}

}  // namespace rfd
