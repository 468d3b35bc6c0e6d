#include "core/exr_file.hpp"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFloatAttribute.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfThreading.h>
#include <OpenEXR/ImfVersion.h>
#include <Imath/half.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/half.hpp"

namespace rfd {
namespace {

// The lossless compressions, by OpenImageIO's names; the lossy ones (pxr24, b44, dwa) are
// left to OpenImageIO, which names their levels.
constexpr std::array<std::pair<const char*, Imf::Compression>, 5> kCompressions{{
    {"none", Imf::NO_COMPRESSION},
    {"rle", Imf::RLE_COMPRESSION},
    {"zips", Imf::ZIPS_COMPRESSION},
    {"zip", Imf::ZIP_COMPRESSION},
    {"piz", Imf::PIZ_COMPRESSION},
}};

std::optional<Imf::Compression> compression_named(const std::string& name) {
    for (const auto& [known, compression] : kCompressions)
        if (name == known) return compression;
    return std::nullopt;
}

const char* compression_name(Imf::Compression compression) {
    for (const auto& [name, known] : kCompressions)
        if (compression == known) return name;
    return nullptr;
}

// The channels of a file with `count` colour channels, as OpenImageIO names them.
std::vector<std::string> channel_names(int count) {
    switch (count) {
        case 1: return {"Y"};
        case 3: return {"R", "G", "B"};
        case 4: return {"R", "G", "B", "A"};
        default: return {};
    }
}

// OpenEXR compresses a file's blocks of rows on a pool of threads (OpenImageIO sets the
// same); the bytes do not depend on how many.
void start_threads() {
    static std::once_flag once;
    std::call_once(once, [] { Imf::setGlobalThreadCount(static_cast<int>(std::max(1u, std::thread::hardware_concurrency()))); });
}

// The first line of an exception's message: OpenEXR repeats the file's name and context.
std::string first_line(const std::exception& e) {
    const std::string what = e.what();
    return what.substr(0, what.find('\n'));
}

bool starts_as_exr(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::array<char, 4> magic{};
    return in.read(magic.data(), magic.size()) && std::memcmp(magic.data(), "\x76\x2f\x31\x01", 4) == 0;
}

// OpenImageIO's conversion of a float to an integer sample (its scaled_conversion): scaled,
// rounded half away from zero, clamped; NaN, which it leaves undefined, to 0.
template <typename Int>
Int to_integer_sample(float value) {
    constexpr float scale = static_cast<float>(std::numeric_limits<Int>::max());
    float s = value * scale;
    s += s < 0.0f ? -0.5f : 0.5f;
    return static_cast<Int>(std::isnan(s) ? 0.0f : std::clamp(s, 0.0f, scale));
}

// The frame buffer of rows [y0, y1) of interleaved samples at `rows`, one slice per channel.
Imf::FrameBuffer interleaved_rows(const std::vector<std::string>& channels, SampleType type, const void* rows,
                                  int width, int y0, int y1) {
    const Imf::PixelType pixel = type == SampleType::Half ? Imf::HALF : Imf::FLOAT;
    const std::size_t sample = sample_size(type);
    const std::size_t x_stride = sample * channels.size();
    const std::size_t y_stride = x_stride * static_cast<std::size_t>(width);
    Imf::FrameBuffer frame;
    for (std::size_t c = 0; c < channels.size(); ++c)
        frame.insert(channels[c], Imf::Slice::Make(pixel, static_cast<const char*>(rows) + c * sample,
                                                   Imath::V2i(0, y0), width, y1 - y0, x_stride, y_stride));
    return frame;
}

class ExrReader final : public ImageFileReader::Backend {
public:
    ExrReader(std::unique_ptr<Imf::InputFile> file, ImageFileSpec spec, std::vector<std::string> channels)
        : file_(std::move(file)), spec_(std::move(spec)), channels_(std::move(channels)) {}

    const ImageFileSpec& spec() const override { return spec_; }

    bool read_rows(int y0, int y1, SampleType type, void* out) override {
        try {
            if (type == SampleType::Float32 || type == SampleType::Half) {
                read(y0, y1, type, out);
                return true;
            }
            std::vector<float> rows(static_cast<std::size_t>(spec_.width) * channels_.size() *
                                    static_cast<std::size_t>(y1 - y0));
            read(y0, y1, SampleType::Float32, rows.data());
            if (type == SampleType::UInt8)
                std::transform(rows.begin(), rows.end(), static_cast<std::uint8_t*>(out), to_integer_sample<std::uint8_t>);
            else
                std::transform(rows.begin(), rows.end(), static_cast<std::uint16_t*>(out), to_integer_sample<std::uint16_t>);
            return true;
        } catch (const std::exception& e) {
            error_ = first_line(e);
            return false;
        }
    }

    std::string error() override { return error_.empty() ? "unknown error" : error_; }

private:
    void read(int y0, int y1, SampleType type, void* out) {
        file_->setFrameBuffer(interleaved_rows(channels_, type, out, spec_.width, y0, y1));
        file_->readPixels(y0, y1 - 1);
    }

    std::unique_ptr<Imf::InputFile> file_;
    ImageFileSpec spec_;
    std::vector<std::string> channels_;  ///< the colour channels, in the order read
    std::string error_;
};

// The spec of a covered file as OpenImageIO reads it, or nothing when the file is not one
// this reader covers.
std::optional<ImageFileSpec> covered_spec(const Imf::InputFile& file, std::vector<std::string>& colour) {
    const int version = file.version();
    if (Imf::isTiled(version) || Imf::isMultiPart(version) || Imf::isNonImage(version)) return std::nullopt;
    const Imf::Header& header = file.header();
    const Imath::Box2i window = header.dataWindow();
    constexpr int kLargest = 1 << 30;  // beyond, width and height would overflow an int
    if (window.min != Imath::V2i(0, 0) || window.max.x < 0 || window.max.y < 0 || window.max.x >= kLargest ||
        window.max.y >= kLargest)
        return std::nullopt;
    const char* compression = compression_name(header.compression());
    if (compression == nullptr) return std::nullopt;

    std::vector<std::string> names;
    std::optional<Imf::PixelType> type;
    for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
        const Imf::Channel& channel = it.channel();
        if (channel.xSampling != 1 || channel.ySampling != 1 || (type && *type != channel.type)) return std::nullopt;
        type = channel.type;
        names.emplace_back(it.name());
    }
    if (!type || (*type != Imf::HALF && *type != Imf::FLOAT)) return std::nullopt;
    std::sort(names.begin(), names.end());
    const bool alpha = std::binary_search(names.begin(), names.end(), std::string("A"));
    const int count = static_cast<int>(names.size()) - (alpha ? 1 : 0);
    if (count != 1 && count != 3) return std::nullopt;
    colour = channel_names(count);
    std::vector<std::string> expected = colour;
    if (alpha) expected.emplace_back("A");
    std::sort(expected.begin(), expected.end());
    if (names != expected) return std::nullopt;

    ImageFileSpec spec;
    spec.width = window.max.x + 1;
    spec.height = window.max.y + 1;
    spec.channels = count;
    spec.type = *type == Imf::HALF ? SampleType::Half : SampleType::Float32;
    spec.compression = compression;
    for (auto it = header.begin(); it != header.end(); ++it) {
        const std::string name = it.name();
        const Imf::Attribute& attribute = it.attribute();
        const std::string kind = attribute.typeName();
        const auto* text = kind == "string" ? static_cast<const Imf::StringAttribute*>(&attribute) : nullptr;
        const auto* number = kind == "float" ? static_cast<const Imf::FloatAttribute*>(&attribute) : nullptr;
        if (name.rfind(kAttributePrefix, 0) == 0) {
            if (!text) return std::nullopt;
            spec.attributes[name.substr(std::strlen(kAttributePrefix))] = text->value();
        } else if (name == "xDensity") {
            // OpenImageIO: EXR's density is per inch, and its pixel aspect ratio (pixel width
            // over height) gives the vertical one.
            if (!number) return std::nullopt;
            spec.dpi_x = number->value();
            spec.dpi_y = number->value() * header.pixelAspectRatio();
        } else if (name == "comments") {
            if (!text) return std::nullopt;
            spec.description = text->value();
        } else if (name == "expTime") {
            if (!number) return std::nullopt;
            spec.exposure_seconds = static_cast<double>(number->value());
        } else if (name == "ResolutionUnit") {
            if (!text || text->value() != "in") return std::nullopt;
        } else if (name == "XResolution" || name == "YResolution" || name == "ImageDescription" ||
                   name == "ExposureTime") {
            return std::nullopt;  // OpenImageIO's own names, which it would read as they are
        }
    }
    // OpenImageIO reads a float as a float and a half as a half: both round trip exactly.
    return spec;
}

// Writes through a FILE* of its own, so that a failed write is noticed where it happens and
// the last buffered bytes are flushed and checked on closing.
class FileStream final : public Imf::OStream {
public:
    FileStream(std::FILE* file, const std::string& path) : Imf::OStream(path.c_str()), file_(file) {}
    void write(const char c[], int n) override {
        if (std::fwrite(c, 1, static_cast<std::size_t>(n), file_) != static_cast<std::size_t>(n)) fail();
    }
    uint64_t tellp() override { return static_cast<uint64_t>(ftello(file_)); }
    void seekp(uint64_t pos) override {
        if (fseeko(file_, static_cast<off_t>(pos), SEEK_SET) != 0) fail();
    }
    const std::string& failure() const { return failure_; }

private:
    [[noreturn]] void fail() {
        if (failure_.empty()) failure_ = std::string("writing failed: ") + std::strerror(errno);
        throw std::runtime_error(failure_);
    }
    std::FILE* file_;
    std::string failure_;
};

class ExrWriter final : public ImageFileWriter::Backend {
public:
    ExrWriter(std::FILE* file, const std::string& path, const Imf::Header& header, const ImageFileSpec& spec)
        : file_(file), stream_(file, path), width_(spec.width), type_(spec.type), names_(channel_names(spec.channels)),
          output_(std::make_unique<Imf::OutputFile>(stream_, header)) {}
    ~ExrWriter() override {
        output_.reset();
        if (file_) std::fclose(file_);
    }

    bool write_rows(int y0, int y1, SampleType type, const void* rows) override {
        if (type != SampleType::Half && type != SampleType::Float32) {
            error_ = std::string("rfd writes EXR samples from half or float rows, not ") + sample_type_name(type);
            return false;
        }
        try {
            const std::size_t count = static_cast<std::size_t>(width_) * names_.size() * static_cast<std::size_t>(y1 - y0);
            // Rows of the other type are converted as OpenImageIO converts them (Imath's rounding).
            if (type != type_) {
                converted_.resize(count * sample_size(type_));
                if (type_ == SampleType::Half) {
                    floats_to_half({static_cast<const float*>(rows), count},
                                   {reinterpret_cast<std::uint16_t*>(converted_.data()), count});
                } else {
                    const auto* bits = static_cast<const std::uint16_t*>(rows);
                    auto* floats = reinterpret_cast<float*>(converted_.data());
                    for (std::size_t i = 0; i < count; ++i) floats[i] = Imath::half(Imath::half::FromBits, bits[i]);
                }
                rows = converted_.data();
            }
            output_->setFrameBuffer(interleaved_rows(names_, type_, rows, width_, y0, y1));
            output_->writePixels(y1 - y0);
            return true;
        } catch (const std::exception& e) {
            error_ = stream_.failure().empty() ? first_line(e) : stream_.failure();
            return false;
        }
    }

    bool close() override {
        // OpenEXR writes the table of row offsets when the file object goes, and swallows a
        // failure there: the stream's own record of it, and the flush, tell.
        output_.reset();
        const bool flushed = std::fflush(file_) == 0 && !std::ferror(file_);
        const bool closed = std::fclose(std::exchange(file_, nullptr)) == 0;
        if (!stream_.failure().empty()) error_ = stream_.failure();
        else if (!(flushed && closed)) error_ = "writing failed (disk full?)";
        return stream_.failure().empty() && flushed && closed;
    }

    std::string error() override { return error_.empty() ? "unknown error" : error_; }

private:
    std::FILE* file_;
    FileStream stream_;
    int width_;
    SampleType type_;  ///< as stored in the file
    std::vector<std::string> names_;
    std::vector<std::byte> converted_;  ///< rows converted to type_, reused
    std::unique_ptr<Imf::OutputFile> output_;
    std::string error_;
};

}  // namespace

std::unique_ptr<ImageFileReader::Backend> open_exr_file(const std::string& path) {
    if (!starts_as_exr(path)) return nullptr;
    start_threads();
    try {
        auto file = std::make_unique<Imf::InputFile>(path.c_str());
        std::vector<std::string> colour;
        std::optional<ImageFileSpec> spec = covered_spec(*file, colour);
        if (!spec) return nullptr;
        return std::make_unique<ExrReader>(std::move(file), std::move(*spec), std::move(colour));
    } catch (const std::exception&) {
        return nullptr;  // OpenImageIO says what is wrong with it, as it always has
    }
}

bool exr_file_covers(const ImageFileSpec& spec) {
    return !channel_names(spec.channels).empty() && (spec.type == SampleType::Half || spec.type == SampleType::Float32) &&
           (spec.compression.empty() || compression_named(spec.compression)) && spec.description.empty() &&
           !spec.exposure_seconds && !spec.focal_length_35mm;
}

std::unique_ptr<ImageFileWriter::Backend> create_exr_file(const std::string& path, const ImageFileSpec& spec,
                                                          std::string& error) {
    RFD_CHECK(exr_file_covers(spec));
    start_threads();
    // The header OpenImageIO writes for the same spec (core/imageio_module.cpp: oiio_spec):
    // zip unless told, the fixed date, the print resolution as a density per inch and a
    // pixel aspect ratio, rfd's attributes as strings.
    const bool has_dpi = spec.dpi_x > 0.0 && spec.dpi_y > 0.0;
    const float aspect = has_dpi ? static_cast<float>(spec.dpi_y / spec.dpi_x) : 1.0f;
    const Imf::Compression compression = spec.compression.empty() ? Imf::ZIP_COMPRESSION : *compression_named(spec.compression);
    Imf::Header header(spec.width, spec.height, aspect, Imath::V2f(0.0f, 0.0f), 1.0f, Imf::INCREASING_Y, compression);
    const Imf::PixelType pixel = spec.type == SampleType::Half ? Imf::HALF : Imf::FLOAT;
    for (const std::string& name : channel_names(spec.channels)) header.channels().insert(name, Imf::Channel(pixel));
    header.insert("capDate", Imf::StringAttribute(kFixedImageDate));
    if (has_dpi) {
        header.insert("ResolutionUnit", Imf::StringAttribute("in"));
        header.insert("xDensity", Imf::FloatAttribute(static_cast<float>(spec.dpi_x)));
    }
    for (const auto& [key, value] : spec.attributes) header.insert(kAttributePrefix + key, Imf::StringAttribute(value));

    std::FILE* file = std::fopen(path.c_str(), "wb");
    if (!file) {
        error = std::string("cannot create the file: ") + std::strerror(errno);
        return nullptr;
    }
    try {
        return std::make_unique<ExrWriter>(file, path, header, spec);
    } catch (const std::exception& e) {
        // The writer's destructor did not run: the file is still open.
        std::fclose(file);
        error = first_line(e);
        return nullptr;
    }
}

}  // namespace rfd
