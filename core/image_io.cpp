#include "core/image_io.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <memory>
#include <string>

#include "core/error.hpp"
#include "core/image_file.hpp"

namespace rfd {

std::string lower_extension(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

bool is_linear_format(const std::filesystem::path& path) {
    const std::string ext = lower_extension(path);
    return ext == ".exr" || ext == ".hdr";
}

ImageSize read_image_size(const std::filesystem::path& path) {
    const ImageFileReader file(path);
    return {file.spec().width, file.spec().height, file.spec().channels};
}

namespace {

// Rows longer than this are a broken or hostile header, not a photograph of a light stage.
constexpr double kMaxRowSamples = 1 << 26;

// The linear value of every 8- or 16-bit sRGB code: the decoding read_image() applies, once.
template <typename Code>
const std::vector<float>& linear_table() {
    static const std::vector<float> table = [] {
        constexpr std::size_t codes = std::size_t{1} << (8 * sizeof(Code));
        constexpr float top = static_cast<float>(codes - 1);
        std::vector<float> values(codes);
        for (std::size_t v = 0; v < codes; ++v) values[v] = srgb_to_linear(static_cast<float>(v) / top);
        return values;
    }();
    return table;
}

// Band samples (interleaved, `width` pixels a row) of columns [x0, x1) into `out`, planar.
template <typename Sample, typename Decode>
void deinterleave(const std::vector<Sample>& band, int width, int channels, int x0, Image& out, Decode decode) {
    for (int y = 0; y < out.height(); ++y)
        for (int c = 0; c < channels; ++c) {
            const Sample* in = band.data() + (static_cast<std::size_t>(y) * width + x0) * channels + c;
            float* row = out.plane(c).data() + static_cast<std::size_t>(y) * out.width();
            for (int x = 0; x < out.width(); ++x) row[x] = decode(in[static_cast<std::size_t>(x) * channels]);
        }
}

}  // namespace

ImageBandReader::ImageBandReader(const std::filesystem::path& path) : file_(path) {
    const ImageFileSpec& spec = file_.spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.channels <= 0)
        throw InputError(SourceLocation{path.string()}, "image has no pixels");
    if (static_cast<double>(spec.width) * spec.channels > kMaxRowSamples)
        throw InputError(SourceLocation{path.string()},
                         "the header declares rows of " + std::to_string(spec.width) + " pixels of " +
                             std::to_string(spec.channels) + " channel(s), more than the " +
                             std::to_string(static_cast<long>(kMaxRowSamples)) + " samples a row may hold");
}

Image ImageBandReader::read(int y0, int y1, int x0, int x1) {
    if (x1 == 0) x1 = width();
    RFD_CHECK(0 <= y0 && y0 < y1 && y1 <= height() && 0 <= x0 && x0 < x1 && x1 <= width());
    const int channels = this->channels();
    const std::size_t samples = static_cast<std::size_t>(y1 - y0) * width() * channels;
    Image out(x1 - x0, y1 - y0, channels);
    switch (file_.spec().type) {
    case SampleType::UInt8: {
        bytes_.resize(samples);
        file_.read_rows(y0, y1, SampleType::UInt8, bytes_.data());
        const float* table = linear_table<std::uint8_t>().data();
        deinterleave(bytes_, width(), channels, x0, out, [table](std::uint8_t v) { return table[v]; });
        break;
    }
    case SampleType::UInt16: {
        words_.resize(samples);
        file_.read_rows(y0, y1, SampleType::UInt16, words_.data());
        const float* table = linear_table<std::uint16_t>().data();
        deinterleave(words_, width(), channels, x0, out, [table](std::uint16_t v) { return table[v]; });
        break;
    }
    default:
        floats_.resize(samples);
        file_.read_rows(y0, y1, SampleType::Float32, floats_.data());
        for (std::size_t k = 0; k < samples; ++k)
            if (!std::isfinite(floats_[k])) {
                const std::size_t pixel = k / channels;
                throw InputError(SourceLocation{path().string()},
                                 "pixel (" + std::to_string(pixel % width()) + ", " +
                                     std::to_string(y0 + pixel / width()) + ") channel " +
                                     std::to_string(k % channels) + " is not a finite number");
            }
        deinterleave(floats_, width(), channels, x0, out, [](float v) { return v; });
    }
    return out;
}

void check_whole_image_size(const std::filesystem::path& path, const ImageSize& size) {
    // Held whole in memory: a header declaring more than this is a broken or hostile file.
    constexpr double kMaxSamples = 1 << 30;
    const double samples = static_cast<double>(size.width) * size.height * size.channels;
    if (samples > kMaxSamples)
        throw InputError(SourceLocation{path.string()},
                         "the header declares " + std::to_string(size.width) + " x " + std::to_string(size.height) +
                             " pixels of " + std::to_string(size.channels) + " channel(s), more than the " +
                             std::to_string(static_cast<long>(kMaxSamples)) + " samples an image may hold");
}

Image read_image(const std::filesystem::path& path) {
    ImageBandReader file(path);
    check_whole_image_size(path, {file.width(), file.height(), file.channels()});
    return file.read(0, file.height());
}

ImageBandWriter::ImageBandWriter(const std::filesystem::path& path, int width, int height, int channels,
                                 const std::string& compression)
    : path_(path), width_(width), height_(height), channels_(channels) {
    RFD_CHECK(width > 0 && height > 0 && channels > 0);
    const std::string ext = lower_extension(path);
    ImageFileSpec spec{.width = width, .height = height, .channels = channels};
    spec.compression = compression;
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg") {
        spec.type = SampleType::UInt8;
        srgb_ = true;
    } else if (ext == ".tif" || ext == ".tiff") {
        spec.type = SampleType::UInt16;
        srgb_ = true;
    } else if (ext == ".exr") {
        if (spec.compression.empty()) spec.compression = "zip";
    } else if (ext != ".hdr") {
        throw InputError(SourceLocation{path.string()},
                         "unknown image extension '" + ext + "' (expected .exr, .hdr, .png, .jpg, .tif)");
    }
    file_ = std::make_unique<ImageFileWriter>(path, spec);
}

void ImageBandWriter::write(const Image& band) {
    RFD_CHECK(band.width() == width_ && band.channels() == channels_ && next_row_ + band.height() <= height_);
    interleaved_.resize(band.pixel_count() * static_cast<std::size_t>(channels_));
    std::size_t k = 0;
    for (int y = 0; y < band.height(); ++y)
        for (int x = 0; x < width_; ++x)
            for (int c = 0; c < channels_; ++c) {
                const float v = band.at(x, y, c);
                if (!std::isfinite(v))
                    throw InputError(SourceLocation{path_.string()},
                                     "refusing to write pixel (" + std::to_string(x) + ", " +
                                         std::to_string(next_row_ + y) + ") channel " + std::to_string(c) +
                                         ": not a finite number");
                interleaved_[k++] = srgb_ ? linear_to_srgb(std::clamp(v, 0.0f, 1.0f)) : v;
            }
    file_->write_rows(next_row_, next_row_ + band.height(), interleaved_);
    next_row_ += band.height();
}

void ImageBandWriter::finish() {
    RFD_CHECK(next_row_ == height_);
    file_->finish();
}

void write_image(const std::filesystem::path& path, const Image& image, const std::string& compression) {
    RFD_CHECK(!image.empty());
    ImageBandWriter file(path, image.width(), image.height(), image.channels(), compression);
    file.write(image);
    file.finish();
}

}  // namespace rfd
