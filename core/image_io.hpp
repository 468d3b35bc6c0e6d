#pragma once
// Reading and writing images through OpenImageIO, with the colour decoding rfd relies on.
//
// Reading: float formats (EXR, HDR, float TIFF) are taken as linear; integer formats
// (8- or 16-bit PNG, TIFF, JPEG) as sRGB-encoded and decoded to linear. An alpha channel is
// dropped: fields and patterns carry colour only. Non-finite samples are an error.
// Writing, by extension: .exr as 32-bit float (exact round trip), .hdr as RGBE, .png and
// .jpg as 8-bit sRGB, .tif/.tiff as 16-bit sRGB; integer encodings clamp to [0, 1].
// Files are written to a temporary sibling and renamed into place.
//
// Example: Image image = read_image("field/img_000.exr"); write_image("preview.png", image);

#include <filesystem>
#include <string>

#include "core/image.hpp"

namespace rfd {

/// Width and height of an image file, without reading its pixels.
struct ImageSize {
    int width = 0;
    int height = 0;
    int channels = 0;  ///< colour channels (alpha excluded)
};

/// Reads `path`. Throws IoError when it is missing or unreadable, InputError when a sample
/// is NaN or infinite (naming the pixel).
Image read_image(const std::filesystem::path& path);
ImageSize read_image_size(const std::filesystem::path& path);

/// Writes `image` to `path` in the encoding its extension selects, with the format's
/// `compression` when given ("jpeg:80": a JPEG of quality 80). Throws InputError for a
/// non-finite sample (nothing is written) and IoError when writing fails.
void write_image(const std::filesystem::path& path, const Image& image, const std::string& compression = "");

/// The extension of `path` in lower case, with its dot (".exr"), as writers choose formats.
std::string lower_extension(const std::filesystem::path& path);
/// True for the extensions write_image() and read_image() treat as linear float.
bool is_linear_format(const std::filesystem::path& path);

}  // namespace rfd
