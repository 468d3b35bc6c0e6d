// librfd_imageio.so: rfd's image files (core/image_backend.hpp) on OpenImageIO. Adaptor
// code only; it links OpenImageIO and nothing of rfd.

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/image_backend.hpp"

namespace rfd {
namespace {

constexpr double kCentimetresPerInch = 2.54;

OIIO::TypeDesc type_desc(SampleType type) {
    switch (type) {
        case SampleType::UInt8: return OIIO::TypeDesc::UINT8;
        case SampleType::UInt16: return OIIO::TypeDesc::UINT16;
        case SampleType::Half: return OIIO::TypeDesc::HALF;
        case SampleType::Float32: return OIIO::TypeDesc::FLOAT;
    }
    return OIIO::TypeDesc::FLOAT;
}

// Files of other integer or float types are read as the nearest of rfd's four.
SampleType sample_type(OIIO::TypeDesc desc) {
    if (desc == OIIO::TypeDesc::UINT8) return SampleType::UInt8;
    if (desc == OIIO::TypeDesc::HALF) return SampleType::Half;
    if (desc.is_floating_point()) return SampleType::Float32;
    return SampleType::UInt16;
}

ImageFileSpec spec_of(const OIIO::ImageSpec& spec) {
    ImageFileSpec out;
    out.width = spec.width;
    out.height = spec.height;
    // Alpha is dropped; it is the last channel in every format rfd reads.
    out.channels = spec.alpha_channel >= 0 && spec.nchannels > 1 ? spec.nchannels - 1 : spec.nchannels;
    out.type = sample_type(spec.format);
    const double per_inch = spec.get_string_attribute("ResolutionUnit") == "cm" ? kCentimetresPerInch : 1.0;
    out.dpi_x = spec.get_float_attribute("XResolution", 0.0f) * per_inch;
    out.dpi_y = spec.get_float_attribute("YResolution", 0.0f) * per_inch;
    out.description = spec.get_string_attribute("ImageDescription");
    out.compression = spec.get_string_attribute("compression");
    if (const OIIO::ParamValue* time = spec.find_attribute("ExposureTime"))
        out.exposure_seconds = static_cast<double>(time->get_float());
    if (const OIIO::ParamValue* focal = spec.find_attribute("Exif:FocalLengthIn35mmFilm"))
        if (focal->get_float() > 0.0f) out.focal_length_35mm = static_cast<double>(focal->get_float());
    const std::string prefix = kAttributePrefix;
    for (const OIIO::ParamValue& p : spec.extra_attribs) {
        const std::string name = p.name().string();
        if (name.rfind(prefix, 0) == 0) out.attributes[name.substr(prefix.size())] = p.get_string();
    }
    return out;
}

OIIO::ImageSpec oiio_spec(const ImageFileSpec& spec) {
    OIIO::ImageSpec out(spec.width, spec.height, spec.channels, type_desc(spec.type));
    if (spec.dpi_x > 0.0 && spec.dpi_y > 0.0) {
        out.attribute("XResolution", static_cast<float>(spec.dpi_x));
        out.attribute("YResolution", static_cast<float>(spec.dpi_y));
        out.attribute("ResolutionUnit", "in");
        // Pixel width over height, i.e. dpi_y / dpi_x: OpenImageIO's TIFF writer stores the
        // y resolution as XResolution times this, and drops YResolution without it.
        out.attribute("PixelAspectRatio", static_cast<float>(spec.dpi_y / spec.dpi_x));
    }
    // Identical images must give identical files: OpenImageIO's writers stamp the current
    // time (EXR's capDate, TIFF's DateTime) unless DateTime is set.
    out.attribute("DateTime", kFixedImageDate);
    if (!spec.compression.empty()) out.attribute("compression", spec.compression);
    if (!spec.jpeg_subsampling.empty()) out.attribute("jpeg:subsampling", spec.jpeg_subsampling);
    if (!spec.description.empty()) out.attribute("ImageDescription", spec.description);
    if (spec.exposure_seconds) out.attribute("ExposureTime", static_cast<float>(*spec.exposure_seconds));
    if (spec.focal_length_35mm)
        out.attribute("Exif:FocalLengthIn35mmFilm", static_cast<int>(std::lround(*spec.focal_length_35mm)));
    for (const auto& [key, value] : spec.attributes) out.attribute(kAttributePrefix + key, value);
    return out;
}

class Input final : public ImageFileReader::Backend {
public:
    explicit Input(std::unique_ptr<OIIO::ImageInput> input) : input_(std::move(input)), spec_(spec_of(input_->spec())) {}
    const ImageFileSpec& spec() const override { return spec_; }
    bool read_rows(int y0, int y1, SampleType type, void* out) override {
        const OIIO::ImageSpec& spec = input_->spec();
        if (spec.tile_width <= 0) return read_scanlines(y0, y1, type_desc(type), out);
        // A tiled file (what `oiiotool --tile` and compositing tools write) is read a row of
        // tiles at a time: read_scanlines on one crashes OpenImageIO 2.4 (SIGFPE).
        const int tile_height = spec.tile_height;
        const int first = spec.y + (y0 - spec.y) / tile_height * tile_height;
        const int last = std::min(spec.y + spec.height, spec.y + (y1 - spec.y + tile_height - 1) / tile_height * tile_height);
        const std::size_t row_bytes = static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec_.channels) *
                                      type_desc(type).size();
        std::vector<std::byte> tiles(row_bytes * static_cast<std::size_t>(last - first));
        if (!input_->read_tiles(0, 0, spec.x, spec.x + spec.width, first, last, 0, 1, 0, spec_.channels, type_desc(type),
                                tiles.data()))
            return false;
        std::memcpy(out, tiles.data() + row_bytes * static_cast<std::size_t>(y0 - first),
                    row_bytes * static_cast<std::size_t>(y1 - y0));
        return true;
    }
    std::string error() override { return input_->geterror(); }

private:
    // OpenImageIO 2.4's read_scanlines allocates a 64 MB buffer on every call, however few
    // rows are asked for and whatever their type: a pattern read a strip at a time paid for
    // a fresh mapping per strip (a minute of page faults under the sanitizers). Rows of a
    // file whose channels share one type are read as stored: straight into `out` when that
    // is the type asked for, else a bounded band at a time into a buffer kept here and
    // converted by OpenImageIO's own conversion.
    bool read_scanlines(int y0, int y1, OIIO::TypeDesc type, void* out) {
        const OIIO::ImageSpec& spec = input_->spec();
        if (!spec.channelformats.empty() || spec_.channels != spec.nchannels)
            return input_->read_scanlines(0, 0, y0, y1, 0, 0, spec_.channels, type, out);
        if (type == spec.format) return input_->read_native_scanlines(0, 0, y0, y1, 0, 0, spec.nchannels, out);
        constexpr std::size_t kBandBytes = std::size_t{8} << 20;
        const std::size_t row_values = static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.nchannels);
        const std::size_t row_bytes = std::max<std::size_t>(1, row_values * spec.format.size());
        const int band = static_cast<int>(std::clamp<std::size_t>(kBandBytes / row_bytes, 1, 4096));
        auto* to = static_cast<std::byte*>(out);
        for (int y = y0; y < y1; y += band) {
            const int rows = std::min(band, y1 - y);
            const std::size_t values = row_values * static_cast<std::size_t>(rows);
            stored_.resize(values * spec.format.size());
            if (!input_->read_native_scanlines(0, 0, y, y + rows, 0, 0, spec.nchannels, stored_.data()) ||
                !OIIO::convert_pixel_values(spec.format, stored_.data(), type, to, static_cast<int>(values)))
                return false;
            to += values * type.size();
        }
        return true;
    }

    std::unique_ptr<OIIO::ImageInput> input_;
    ImageFileSpec spec_;
    std::vector<std::byte> stored_;  // rows as the file stores them, reused between reads
};

// Writes through a FILE* of its own (OpenImageIO's IOFile proxy over it; none for TIFF), so
// that the last buffered bytes are flushed and checked here: OpenImageIO's own close of a
// PNG, EXR or HDR file does not notice when they fail, and a file cut short would look whole.
class Output final : public ImageFileWriter::Backend {
public:
    Output(std::FILE* file, std::unique_ptr<OIIO::Filesystem::IOFile> proxy, std::unique_ptr<OIIO::ImageOutput> output)
        : file_(file), proxy_(std::move(proxy)), output_(std::move(output)) {}
    ~Output() override {
        output_.reset();
        proxy_.reset();
        if (file_) std::fclose(file_);
    }
    // Some writers (PNG) note a failed write as an error but still return true: ask.
    bool write_rows(int y0, int y1, SampleType type, const void* rows) override {
        return output_->write_scanlines(y0, y1, 0, type_desc(type), rows) && !take_errors();
    }
    bool close() override {
        bool ok = output_->close();
        ok = !take_errors() && ok;
        output_.reset();
        proxy_.reset();
        if (!file_) return ok;
        const bool flushed = std::fflush(file_) == 0 && !std::ferror(file_);
        const bool closed = std::fclose(std::exchange(file_, nullptr)) == 0;
        if (ok && !(flushed && closed)) error_ = "writing failed (disk full?)";
        return ok && flushed && closed;
    }
    std::string error() override {
        if (output_) take_errors();
        return error_.empty() ? "unknown error" : error_;
    }

private:
    // Moves the writer's errors into error_, the first line only (a failing disk repeats
    // itself); true if there were any. The TIFF writer reports that it wrote no Exif
    // directory on every close, although the file is whole: that one is not an error.
    bool take_errors() {
        if (!output_->has_error()) return false;
        std::istringstream lines(output_->geterror());
        bool any = false;
        for (std::string line; std::getline(lines, line);) {
            if (line.empty() || line.find("TIFFWriteCustomDirectory() of the Exif data") != std::string::npos) continue;
            if (!any) error_ = line;
            any = true;
        }
        return any;
    }

    std::FILE* file_;  ///< null when the writer opened the file itself
    std::unique_ptr<OIIO::Filesystem::IOFile> proxy_;
    std::unique_ptr<OIIO::ImageOutput> output_;
    std::string error_;
};

class Backend final : public ImageBackend {
public:
    std::unique_ptr<ImageFileReader::Backend> open(const std::string& path, std::string& error) override {
        auto input = OIIO::ImageInput::open(path);
        if (!input) {
            error = OIIO::geterror();
            return nullptr;
        }
        return std::make_unique<Input>(std::move(input));
    }
    std::unique_ptr<ImageFileWriter::Backend> create(const std::string& path, const ImageFileSpec& spec,
                                                     std::string& error) override {
        auto output = OIIO::ImageOutput::create(path);
        if (!output) {
            error = OIIO::geterror();
            return nullptr;
        }
        // libtiff reports its own write failures, and OpenImageIO's TIFF writer through a
        // proxy writes a broken file when it adds Exif data: TIFF opens its file itself.
        std::FILE* file = nullptr;
        std::unique_ptr<OIIO::Filesystem::IOFile> proxy;
        if (std::string(output->format_name()) != "tiff") {
            file = std::fopen(path.c_str(), "wb");
            if (!file) {
                error = std::string("cannot create the file: ") + std::strerror(errno);
                return nullptr;
            }
            proxy = std::make_unique<OIIO::Filesystem::IOFile>(file, OIIO::Filesystem::IOProxy::Write);
        }
        if ((proxy && !output->set_ioproxy(proxy.get())) || !output->open(path, oiio_spec(spec))) {
            error = output->geterror();
            output.reset();
            proxy.reset();
            if (file) std::fclose(file);
            return nullptr;
        }
        return std::make_unique<Output>(file, std::move(proxy), std::move(output));
    }
};

}  // namespace
}  // namespace rfd

extern "C" __attribute__((visibility("default"))) rfd::ImageBackend* rfd_imageio_backend() {
    static rfd::Backend backend;
    return &backend;
}
