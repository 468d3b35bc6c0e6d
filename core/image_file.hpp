#pragma once
// Image files read and written a strip of rows at a time, through OpenImageIO.
//
// This is the one door to image files in rfd: whole images (core/image_io.hpp), pattern
// rasters of hundreds of millions of dots, print sheets and camera photographs all pass
// through it. Samples are interleaved (channel fastest), rows top to bottom, and converted
// between the caller's type and the file's as OpenImageIO converts them; no colour encoding
// happens here (core/image_io.hpp decodes sRGB). OpenImageIO itself lives in the module
// librfd_imageio.so (core/module.hpp), loaded when the first file it is needed for is
// opened; common EXR files are read and written with OpenEXR directly (core/exr_file.hpp).
//
// Example: ImageFileWriter out("a.exr", {.width = 4, .height = 2, .channels = 3});
//          out.write_rows(0, 2, samples); out.finish();

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>

namespace rfd {

/// How a file stores its samples, or how a caller hands them over.
enum class SampleType { UInt8, UInt16, Half, Float32 };

/// Bytes per sample of `type`.
std::size_t sample_size(SampleType type);
/// "uint8", "uint16", "half" or "float", as OpenImageIO names them.
const char* sample_type_name(SampleType type);

/// What an image file says about itself: OpenImageIO's ImageSpec, reduced to what rfd
/// reads and writes.
struct ImageFileSpec {
    int width = 0;
    int height = 0;
    int channels = 0;                       ///< colour channels; a file's alpha is dropped on reading
    SampleType type = SampleType::Float32;  ///< as stored in the file
    double dpi_x = 0.0;                     ///< print resolution, dots per inch; 0 when unknown
    double dpi_y = 0.0;
    std::string description;                ///< the ImageDescription text (TIFF, PNG), "" when none
    std::string compression;                ///< written: the format's compression ("zip", "rle"); "" its default
    std::string jpeg_subsampling;           ///< written: a JPEG's chroma sampling ("4:4:4"); "" the library's
    std::optional<double> exposure_seconds; ///< the EXIF ExposureTime of a photograph
    std::optional<double> focal_length_35mm; ///< the EXIF FocalLengthIn35mmFilm, millimetres
    /// rfd's own attributes of an EXR file ("rfd:" + key in its header), key without prefix.
    std::map<std::string, std::string> attributes;
};

/// Reads an image file a strip of rows at a time (OpenImageIO's ImageInput).
class ImageFileReader {
public:
    /// Opens `path`. `what` names the file's role in messages ("image", "pattern"). Throws
    /// IoError naming the file when it is missing or not a readable image.
    explicit ImageFileReader(const std::filesystem::path& path, const std::string& what = "image");
    ~ImageFileReader();
    ImageFileReader(ImageFileReader&&) noexcept;
    ImageFileReader& operator=(ImageFileReader&&) noexcept;

    const ImageFileSpec& spec() const { return spec_; }
    const std::filesystem::path& path() const { return path_; }
    /// Rows [y0, y1) of the colour channels, converted to `type` (width * channels samples a
    /// row), into `out`, which must hold them. Throws IoError when the file cannot be read.
    void read_rows(int y0, int y1, SampleType type, void* out);
    void read_rows(int y0, int y1, std::span<float> out);
    void read_rows(int y0, int y1, std::span<std::uint8_t> out);

    class Backend;

private:
    std::filesystem::path path_;
    std::string what_;
    ImageFileSpec spec_;
    std::unique_ptr<Backend> backend_;
};

/// Writes an image file a strip of rows at a time (OpenImageIO's ImageOutput) into a
/// temporary sibling, which finish() renames into place: a writer destroyed unfinished (an
/// exception, a failed write) leaves nothing at the path. The format follows the extension.
/// The file's date is fixed, so identical samples give identical files.
class ImageFileWriter {
public:
    /// Starts `path` with `spec` (its type, resolution, description, compression and
    /// attributes; exposure_seconds is not written). Throws IoError when it cannot.
    ImageFileWriter(const std::filesystem::path& path, const ImageFileSpec& spec, const std::string& what = "image");
    ~ImageFileWriter();
    ImageFileWriter(const ImageFileWriter&) = delete;
    ImageFileWriter& operator=(const ImageFileWriter&) = delete;

    /// Rows [y0, y1), in order, of `type` samples (width * channels a row).
    void write_rows(int y0, int y1, SampleType type, const void* rows);
    void write_rows(int y0, int y1, std::span<const float> rows);
    /// Closes the file and renames it into place.
    void finish();

    class Backend;

private:
    std::filesystem::path path_, temporary_;
    std::string what_;
    ImageFileSpec spec_;
    std::unique_ptr<Backend> backend_;
};

}  // namespace rfd
