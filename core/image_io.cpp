#include "core/image_io.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <memory>
#include <string>

#include <OpenImageIO/imageio.h>

#include "core/error.hpp"
#include "core/files.hpp"

namespace rfd {
namespace {

std::unique_ptr<OIIO::ImageInput> open_input(const std::filesystem::path& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw IoError(SourceLocation{path.string()}, "cannot open: no such image file");
    auto input = OIIO::ImageInput::open(path.string());
    if (!input)
        throw IoError(SourceLocation{path.string()},
                      "cannot read image: " + OIIO::geterror());
    return input;
}

int colour_channels(const OIIO::ImageSpec& spec) {
    // Alpha is dropped; it is the last channel in every format rfd reads.
    return spec.alpha_channel >= 0 && spec.nchannels > 1 ? spec.nchannels - 1 : spec.nchannels;
}

}  // namespace

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
    auto input = open_input(path);
    const OIIO::ImageSpec& spec = input->spec();
    return {spec.width, spec.height, colour_channels(spec)};
}

Image read_image(const std::filesystem::path& path) {
    auto input = open_input(path);
    const OIIO::ImageSpec& spec = input->spec();
    const int channels = colour_channels(spec);
    if (spec.width <= 0 || spec.height <= 0 || channels <= 0)
        throw InputError(SourceLocation{path.string()}, "image has no pixels");
    std::vector<float> interleaved(static_cast<std::size_t>(spec.width) * spec.height * channels);
    if (!input->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, interleaved.data()))
        throw IoError(SourceLocation{path.string()}, "cannot read image: " + input->geterror());
    const bool srgb = !spec.format.is_floating_point();
    Image image(spec.width, spec.height, channels);
    std::size_t k = 0;
    for (int y = 0; y < spec.height; ++y)
        for (int x = 0; x < spec.width; ++x)
            for (int c = 0; c < channels; ++c) {
                const float v = interleaved[k++];
                if (!std::isfinite(v))
                    throw InputError(SourceLocation{path.string()},
                                     "pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                         ") channel " + std::to_string(c) +
                                         " is not a finite number");
                image.at(x, y, c) = srgb ? srgb_to_linear(v) : v;
            }
    return image;
}

void write_image(const std::filesystem::path& path, const Image& image) {
    RFD_CHECK(!image.empty());
    const std::string ext = lower_extension(path);
    OIIO::TypeDesc format = OIIO::TypeDesc::FLOAT;
    bool srgb = false;
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg") {
        format = OIIO::TypeDesc::UINT8;
        srgb = true;
    } else if (ext == ".tif" || ext == ".tiff") {
        format = OIIO::TypeDesc::UINT16;
        srgb = true;
    } else if (ext != ".exr" && ext != ".hdr") {
        throw InputError(SourceLocation{path.string()},
                         "unknown image extension '" + ext +
                             "' (expected .exr, .hdr, .png, .jpg, .tif)");
    }
    const int channels = image.channels();
    std::vector<float> interleaved(image.pixel_count() * static_cast<std::size_t>(channels));
    std::size_t k = 0;
    for (int y = 0; y < image.height(); ++y)
        for (int x = 0; x < image.width(); ++x)
            for (int c = 0; c < channels; ++c) {
                const float v = image.at(x, y, c);
                if (!std::isfinite(v))
                    throw InputError(SourceLocation{path.string()},
                                     "refusing to write pixel (" + std::to_string(x) + ", " +
                                         std::to_string(y) + ") channel " + std::to_string(c) +
                                         ": not a finite number");
                interleaved[k++] = srgb ? linear_to_srgb(std::clamp(v, 0.0f, 1.0f)) : v;
            }
    const std::filesystem::path temporary = temporary_sibling(path);
    auto output = OIIO::ImageOutput::create(temporary.string());
    if (!output)
        throw IoError(SourceLocation{path.string()}, "cannot write image: " + OIIO::geterror());
    OIIO::ImageSpec spec(image.width(), image.height(), channels, format);
    if (ext == ".exr") spec.attribute("compression", "zip");
    // Identical images must give identical files: OpenImageIO's EXR writer stamps the current
    // time as capDate unless DateTime is set, so set it to a fixed, obviously neutral value.
    spec.attribute("DateTime", "1970:01:01 00:00:00");
    const bool written = output->open(temporary.string(), spec) &&
                         output->write_image(OIIO::TypeDesc::FLOAT, interleaved.data()) &&
                         output->close();
    if (!written) {
        const std::string message = output->geterror();
        std::error_code ec;
        std::filesystem::remove(temporary, ec);
        throw IoError(SourceLocation{path.string()}, "cannot write image: " + message);
    }
    move_into_place(temporary, path);
}

}  // namespace rfd
