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

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/image.hpp"
#include "core/image_file.hpp"

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
/// InputError naming `path` when an image of `size` is too large to hold whole (2^30
/// samples): a broken or hostile header, not a photograph.
void check_whole_image_size(const std::filesystem::path& path, const ImageSize& size);

/// Writes `image` to `path` in the encoding its extension selects, with the format's
/// `compression` when given ("jpeg:80": a JPEG of quality 80). Throws InputError for a
/// non-finite sample (nothing is written) and IoError when writing fails.
void write_image(const std::filesystem::path& path, const Image& image, const std::string& compression = "");

/// An image file read a band of rows at a time, decoded as read_image() decodes it: integer
/// samples through a table of their linear values (no power per sample), float samples
/// checked finite. Bands read in ascending order cost one decode of the file (JPEG and PNG
/// decode sequentially; a band above the last one read starts the file again).
//
// Example: ImageBandReader in("big.jpg");
//          for (int y = 0; y < in.height(); y += 64) use(in.read(y, std::min(y + 64, in.height())));
class ImageBandReader {
public:
    /// Opens `path`; IoError when it is missing or unreadable, InputError for a file
    /// without pixels or with rows too long to hold.
    explicit ImageBandReader(const std::filesystem::path& path);

    int width() const { return file_.spec().width; }
    int height() const { return file_.spec().height; }
    int channels() const { return file_.spec().channels; }
    const std::filesystem::path& path() const { return file_.path(); }
    /// What the file says about itself (EXIF focal length, exposure).
    const ImageFileSpec& spec() const { return file_.spec(); }

    /// Rows [y0, y1) of columns [x0, x1) (the whole width when x1 is 0), linear and planar.
    /// InputError naming the pixel for a sample that is NaN or infinite.
    Image read(int y0, int y1, int x0 = 0, int x1 = 0);

private:
    // Rows of 8- or 16-bit sRGB codes, decoded through their table into `out`.
    template <typename Code>
    void read_codes(std::vector<Code>& buffer, SampleType type, int y0, int y1, int x0, Image& out);

    ImageFileReader file_;
    std::vector<std::uint8_t> bytes_;     // a band of an 8-bit file, as stored, reused
    std::vector<std::uint16_t> words_;    // of a 16-bit file
    std::vector<float> floats_;           // of a float file
};

/// An image file written a band of rows at a time, top to bottom, encoded as write_image()
/// encodes by extension; nothing is at the path until finish() (core/image_file.hpp).
class ImageBandWriter {
public:
    ImageBandWriter(const std::filesystem::path& path, int width, int height, int channels,
                    const std::string& compression = "");
    /// The next band.height() rows; InputError for a non-finite sample (nothing is written).
    void write(const Image& band);
    /// Closes the file and renames it into place; every row must have been written.
    void finish();

private:
    std::filesystem::path path_;
    int width_ = 0, height_ = 0, channels_ = 0, next_row_ = 0;
    bool srgb_ = false;
    bool codes_ = false;  // 8-bit: encoded through encode_srgb8()
    std::unique_ptr<ImageFileWriter> file_;
    std::vector<float> interleaved_;
    std::vector<std::uint8_t> bytes_;
};

/// The 8-bit sRGB code of a linear sample, as 8-bit files are written: clamped to [0, 1],
/// encoded, rounded; through a table of the codes' thresholds.
std::uint8_t encode_srgb8(float linear);
/// The same for every sample of `linear` (finite) into `codes` (as long).
void encode_srgb8(std::span<const float> linear, std::span<std::uint8_t> codes);

/// The extension of `path` in lower case, with its dot (".exr"), as writers choose formats.
std::string lower_extension(const std::filesystem::path& path);
/// True for the extensions write_image() and read_image() treat as linear float.
bool is_linear_format(const std::filesystem::path& path);

}  // namespace rfd
