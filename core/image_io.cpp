#include "core/image_io.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "core/error.hpp"
#include "core/image_file.hpp"
#include "core/parallel.hpp"

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

// The 8-bit code write_image() gives a linear sample: sRGB-encoded, clamped, rounded.
std::uint8_t srgb_code(float linear) {
    return static_cast<std::uint8_t>(std::lround(255.0f * linear_to_srgb(std::clamp(linear, 0.0f, 1.0f))));
}

// thresholds[k]: the least linear value whose code is above k. Found by bisection over the
// non-negative floats' bit patterns (ordered as the floats are), so a search in the table
// gives srgb_code() without a power per sample.
const std::array<float, 255>& srgb_code_thresholds() {
    static const std::array<float, 255> thresholds = [] {
        std::array<float, 255> t{};
        for (int k = 0; k < 255; ++k) {
            std::uint32_t low = 0, high = std::bit_cast<std::uint32_t>(1.0f);  // code(low) <= k < code(high)
            while (high - low > 1) {
                const std::uint32_t middle = low + (high - low) / 2;
                (srgb_code(std::bit_cast<float>(middle)) > k ? high : low) = middle;
            }
            t[static_cast<std::size_t>(k)] = std::bit_cast<float>(high);
        }
        return t;
    }();
    return thresholds;
}

// Per bucket of floats sharing their top 16 bits (those in [0, 1] fill 16257 buckets), the
// code of the bucket's least value. No bucket holds more than one threshold (checked here:
// the codes' steps in linear light are wider than the buckets everywhere in [0, 1]), so a
// sample's code is its bucket's, plus one past the threshold.
const std::vector<std::uint8_t>& srgb_bucket_codes() {
    static const std::vector<std::uint8_t> codes = [] {
        const std::array<float, 255>& t = srgb_code_thresholds();
        std::vector<std::uint8_t> first((std::bit_cast<std::uint32_t>(1.0f) >> 16) + 1);
        for (std::size_t b = 0; b < first.size(); ++b) {
            const auto code_of = [&](std::uint32_t bits) {
                return std::upper_bound(t.begin(), t.end(), std::bit_cast<float>(bits)) - t.begin();
            };
            const auto least = static_cast<std::uint32_t>(b << 16);
            first[b] = static_cast<std::uint8_t>(code_of(least));
            RFD_CHECK(b + 1 == first.size() || code_of(least + 0xFFFF) - code_of(least) <= 1);
        }
        return first;
    }();
    return codes;
}

// The thresholds with +infinity after the last, so code 255 never steps further.
const std::array<float, 256>& srgb_code_steps() {
    static const std::array<float, 256> steps = [] {
        std::array<float, 256> s{};
        std::copy(srgb_code_thresholds().begin(), srgb_code_thresholds().end(), s.begin());
        s[255] = std::numeric_limits<float>::infinity();
        return s;
    }();
    return steps;
}

// encode_srgb8() with its tables in hand (a function-local static costs a guard per call),
// without a branch: samples are finite here (checked before).
inline std::uint8_t encode_srgb8(float linear, const float* steps, const std::uint8_t* bucket_codes) {
    const float v = std::min(std::max(0.0f, linear), 1.0f);  // -0 becomes +0: its bits index no bucket
    const unsigned code = bucket_codes[std::bit_cast<std::uint32_t>(v) >> 16];
    return static_cast<std::uint8_t>(code + (v >= steps[code] ? 1u : 0u));
}

}  // namespace

std::uint8_t encode_srgb8(float linear) {
    if (std::isnan(linear)) return 0;
    return encode_srgb8(linear, srgb_code_steps().data(), srgb_bucket_codes().data());
}

void encode_srgb8(std::span<const float> linear, std::span<std::uint8_t> codes) {
    RFD_CHECK(codes.size() == linear.size());
    const float* steps = srgb_code_steps().data();
    const std::uint8_t* bucket_codes = srgb_bucket_codes().data();
    for (std::size_t k = 0; k < linear.size(); ++k) codes[k] = encode_srgb8(linear[k], steps, bucket_codes);
}

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

template <typename Code>
void ImageBandReader::read_codes(std::vector<Code>& buffer, SampleType type, int y0, int y1, int x0, Image& out) {
    buffer.resize(static_cast<std::size_t>(y1 - y0) * width() * channels());
    file_.read_rows(y0, y1, type, buffer.data());
    const float* table = linear_table<Code>().data();
    deinterleave(buffer, width(), channels(), x0, out, [table](Code v) { return table[v]; });
}

Image ImageBandReader::read(int y0, int y1, int x0, int x1) {
    if (x1 == 0) x1 = width();
    RFD_CHECK(0 <= y0 && y0 < y1 && y1 <= height() && 0 <= x0 && x0 < x1 && x1 <= width());
    const int channels = this->channels();
    const std::size_t samples = static_cast<std::size_t>(y1 - y0) * width() * channels;
    Image out(x1 - x0, y1 - y0, channels);
    switch (file_.spec().type) {
    case SampleType::UInt8: read_codes(bytes_, SampleType::UInt8, y0, y1, x0, out); break;
    case SampleType::UInt16: read_codes(words_, SampleType::UInt16, y0, y1, x0, out); break;
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
        srgb_ = codes_ = true;
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
    for (int c = 0; c < channels_; ++c)
        for (std::size_t p = 0; p < band.pixel_count(); ++p)
            if (!std::isfinite(band.plane(c)[p]))
                throw InputError(SourceLocation{path_.string()},
                                 "refusing to write pixel (" + std::to_string(p % width_) + ", " +
                                     std::to_string(next_row_ + static_cast<int>(p / width_)) + ") channel " +
                                     std::to_string(c) + ": not a finite number");
    if (codes_) {
        // 8 bits: the codes from the table, no power per sample.
        bytes_.resize(band.pixel_count() * static_cast<std::size_t>(channels_));
        const auto channels = static_cast<std::size_t>(channels_);
        const float* steps = srgb_code_steps().data();
        const std::uint8_t* bucket_codes = srgb_bucket_codes().data();
        parallel_for_chunks(band.pixel_count(), 1 << 14, [&](std::size_t begin, std::size_t end) {
            for (std::size_t c = 0; c < channels; ++c) {
                const float* plane = band.plane(static_cast<int>(c)).data();
                for (std::size_t p = begin; p < end; ++p)
                    bytes_[p * channels + c] = encode_srgb8(plane[p], steps, bucket_codes);
            }
        });
        file_->write_rows(next_row_, next_row_ + band.height(), SampleType::UInt8, bytes_.data());
        next_row_ += band.height();
        return;
    }
    interleaved_.resize(band.pixel_count() * static_cast<std::size_t>(channels_));
    std::size_t k = 0;
    for (int y = 0; y < band.height(); ++y)
        for (int x = 0; x < width_; ++x)
            for (int c = 0; c < channels_; ++c) {
                const float v = band.at(x, y, c);
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
