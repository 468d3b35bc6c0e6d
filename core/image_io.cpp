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

Image read_image(const std::filesystem::path& path) {
    ImageFileReader file(path);
    const ImageFileSpec& spec = file.spec();
    const int channels = spec.channels;
    if (spec.width <= 0 || spec.height <= 0 || channels <= 0)
        throw InputError(SourceLocation{path.string()}, "image has no pixels");
    // Held whole in memory, twice while converting: a header declaring more than this is a
    // broken or hostile file, not a photograph of a light stage.
    constexpr double kMaxSamples = 1 << 30;
    const double samples = static_cast<double>(spec.width) * spec.height * channels;
    if (samples > kMaxSamples)
        throw InputError(SourceLocation{path.string()},
                         "the header declares " + std::to_string(spec.width) + " x " + std::to_string(spec.height) +
                             " pixels of " + std::to_string(channels) + " channel(s), more than the " +
                             std::to_string(static_cast<long>(kMaxSamples)) + " samples an image may hold");
    std::vector<float> interleaved(static_cast<std::size_t>(spec.width) * spec.height * channels);
    file.read_rows(0, spec.height, interleaved);
    const bool srgb = spec.type == SampleType::UInt8 || spec.type == SampleType::UInt16;
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

void write_image(const std::filesystem::path& path, const Image& image, const std::string& compression) {
    RFD_CHECK(!image.empty());
    const std::string ext = lower_extension(path);
    ImageFileSpec spec{.width = image.width(), .height = image.height(), .channels = image.channels()};
    spec.compression = compression;
    bool srgb = false;
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg") {
        spec.type = SampleType::UInt8;
        srgb = true;
    } else if (ext == ".tif" || ext == ".tiff") {
        spec.type = SampleType::UInt16;
        srgb = true;
    } else if (ext == ".exr") {
        if (spec.compression.empty()) spec.compression = "zip";
    } else if (ext != ".hdr") {
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
    ImageFileWriter file(path, spec);
    file.write_rows(0, image.height(), interleaved);
    file.finish();
}

}  // namespace rfd
