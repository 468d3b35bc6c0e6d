#include "core/image.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"

namespace rfd {

Image::Image(int width, int height, int channels, float fill)
    : width_(width), height_(height), channels_(channels) {
    RFD_CHECK(width >= 0 && height >= 0 && channels >= 0);
    samples_.assign(pixel_count() * static_cast<std::size_t>(channels), fill);
}

Image Image::exposed(double stops) const {
    Image out = *this;
    const float factor = static_cast<float>(std::exp2(stops));
    for (float& v : out.samples_) v *= factor;
    return out;
}

Image tiled(const std::vector<Image>& images, int columns, int gap, float fill) {
    RFD_CHECK(!images.empty() && columns > 0 && gap >= 0);
    const int w = images.front().width(), h = images.front().height(), c = images.front().channels();
    const int count = static_cast<int>(images.size());
    const int across = std::min(columns, count), rows = (count + columns - 1) / columns;
    Image out(gap + across * (w + gap), gap + rows * (h + gap), c, fill);
    for (int k = 0; k < count; ++k) {
        RFD_CHECK(images[static_cast<std::size_t>(k)].same_shape(images.front()));
        const int x0 = gap + k % columns * (w + gap), y0 = gap + k / columns * (h + gap);
        for (int ch = 0; ch < c; ++ch)
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) out.at(x0 + x, y0 + y, ch) = images[static_cast<std::size_t>(k)].at(x, y, ch);
    }
    return out;
}

Image luminance(const Image& image) {
    Image out(image.width(), image.height(), 1);
    auto dst = out.plane(0);
    const float scale = 1.0f / static_cast<float>(std::max(image.channels(), 1));
    for (int c = 0; c < image.channels(); ++c) {
        const auto src = image.plane(c);
        for (std::size_t p = 0; p < dst.size(); ++p) dst[p] += src[p];
    }
    for (float& v : dst) v *= scale;
    return out;
}

double mean_squared_error(const Image& a, const Image& b) {
    RFD_CHECK(a.same_shape(b));
    if (a.samples().empty()) return 0.0;
    double sum = 0.0;
    const auto sa = a.samples(), sb = b.samples();
    for (std::size_t k = 0; k < sa.size(); ++k) {
        const double d = static_cast<double>(sa[k]) - static_cast<double>(sb[k]);
        sum += d * d;
    }
    return sum / static_cast<double>(sa.size());
}

double psnr_from_mse(double mse, double peak) {
    if (mse == 0.0) return std::numeric_limits<double>::infinity();
    return 10.0 * std::log10(peak * peak / mse);
}

double psnr(const Image& a, const Image& b, double peak) { return psnr_from_mse(mean_squared_error(a, b), peak); }

Image join_side_by_side(const std::vector<const Image*>& panels, int gap, float gap_value) {
    RFD_CHECK(!panels.empty() && gap >= 0);
    int width = gap * static_cast<int>(panels.size() - 1), height = 0;
    const int channels = panels.front()->channels();
    for (const Image* panel : panels) {
        RFD_CHECK(panel->channels() == channels);
        width += panel->width();
        height = std::max(height, panel->height());
    }
    Image out(width, height, channels, gap_value);
    int left = 0;
    for (const Image* panel : panels) {
        for (int c = 0; c < channels; ++c)
            for (int y = 0; y < panel->height(); ++y)
                for (int x = 0; x < panel->width(); ++x) out.at(left + x, y, c) = panel->at(x, y, c);
        left += panel->width() + gap;
    }
    return out;
}

float srgb_to_linear(float encoded) {
    if (encoded <= 0.04045f) return encoded / 12.92f;
    return std::pow((encoded + 0.055f) / 1.055f, 2.4f);
}

float linear_to_srgb(float linear) {
    if (linear <= 0.0031308f) return 12.92f * linear;
    return 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
}

}  // namespace rfd
