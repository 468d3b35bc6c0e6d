#pragma once
// Images: linear float samples, planar.
//
// Sample (x, y) of channel c lives at data[(c * height + y) * width + x]; x runs to the right
// and y down, as in the files (row 0 is the top row). Values are linear radiance or
// transmittance, never gamma-encoded: decoding and encoding happen in image_io only.
// Planar storage keeps the per-channel loops of relighting and encoding contiguous.
//
// Example: Image image(512, 512, 3); image.at(10, 20, 1) = 0.5f;

#include <cstddef>
#include <span>
#include <vector>

namespace rfd {

class Image {
public:
    Image() = default;
    /// A width x height image of `channels` channels, every sample set to `fill`.
    Image(int width, int height, int channels, float fill = 0.0f);

    int width() const { return width_; }
    int height() const { return height_; }
    int channels() const { return channels_; }
    bool empty() const { return samples_.empty(); }
    /// Pixels per channel (width * height).
    std::size_t pixel_count() const {
        return static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
    }
    bool same_shape(const Image& other) const {
        return width_ == other.width_ && height_ == other.height_ && channels_ == other.channels_;
    }

    float& at(int x, int y, int c) { return samples_[index(x, y, c)]; }
    float at(int x, int y, int c) const { return samples_[index(x, y, c)]; }
    /// All samples of channel c, row by row.
    std::span<float> plane(int c) { return {samples_.data() + c * pixel_count(), pixel_count()}; }
    std::span<const float> plane(int c) const {
        return {samples_.data() + c * pixel_count(), pixel_count()};
    }
    /// Every sample, channel after channel.
    std::span<float> samples() { return samples_; }
    std::span<const float> samples() const { return samples_; }

    /// The image with every sample multiplied by 2^stops: a camera's exposure compensation.
    Image exposed(double stops) const;

    friend bool operator==(const Image&, const Image&) = default;

private:
    std::size_t index(int x, int y, int c) const {
        return (static_cast<std::size_t>(c) * static_cast<std::size_t>(height_) +
                static_cast<std::size_t>(y)) *
                   static_cast<std::size_t>(width_) +
               static_cast<std::size_t>(x);
    }

    int width_ = 0;
    int height_ = 0;
    int channels_ = 0;
    std::vector<float> samples_;
};

/// `images` (one shape, at least one) laid out in rows of `columns`, `gap` pixels of `fill`
/// between and around them: a contact sheet, or an atlas with gap 0.
Image tiled(const std::vector<Image>& images, int columns, int gap = 0, float fill = 0.0f);

/// Per-pixel luminance (channel mean) of an image, one channel.
Image luminance(const Image& image);

/// Mean squared error over all samples of two images of the same shape.
double mean_squared_error(const Image& a, const Image& b);
/// Peak signal-to-noise ratio in dB for a given peak value (infinite for identical images).
double psnr(const Image& a, const Image& b, double peak = 1.0);
/// The same from a mean squared error: 10 log10(peak^2 / mse), infinite for mse = 0.
double psnr_from_mse(double mse, double peak);

/// The panels in a row, top-aligned, `gap` pixels of `gap_value` between them (and below
/// the shorter ones). All panels must have the same channel count.
Image join_side_by_side(const std::vector<const Image*>& panels, int gap, float gap_value);

/// sRGB transfer functions (IEC 61966-2-1), on values in [0, 1].
float srgb_to_linear(float encoded);
float linear_to_srgb(float linear);

}  // namespace rfd
