#pragma once
// The interface between rfd_core's image files (core/image_file.hpp) and the module that
// wraps OpenImageIO (core/imageio_module.cpp, built as librfd_imageio.so). Plain virtual
// calls and error strings: the module uses no symbol of rfd's libraries, and core turns a
// failure into an IoError that names the file.

#include <memory>
#include <string>

#include "core/image_file.hpp"

namespace rfd {

/// The prefix of rfd's own attributes in an EXR header ("rfd:field"), both backends.
inline constexpr const char* kAttributePrefix = "rfd:";
/// The date every image file is stamped with (writers stamp the current time unless given
/// one), so that identical samples give identical files.
inline constexpr const char* kFixedImageDate = "1970:01:01 00:00:00";

class ImageFileReader::Backend {
public:
    virtual ~Backend() = default;
    virtual const ImageFileSpec& spec() const = 0;
    /// False on failure; error() says why.
    virtual bool read_rows(int y0, int y1, SampleType type, void* out) = 0;
    virtual std::string error() = 0;
};

class ImageFileWriter::Backend {
public:
    virtual ~Backend() = default;
    virtual bool write_rows(int y0, int y1, SampleType type, const void* rows) = 0;
    virtual bool close() = 0;
    virtual std::string error() = 0;
};

/// What librfd_imageio.so's entry point, rfd_imageio_backend(), returns.
class ImageBackend {
public:
    virtual ~ImageBackend() = default;
    /// The file at `path` opened for reading, or null with `error` set.
    virtual std::unique_ptr<ImageFileReader::Backend> open(const std::string& path, std::string& error) = 0;
    /// A new file at `path` (its format from the extension), or null with `error` set.
    virtual std::unique_ptr<ImageFileWriter::Backend> create(const std::string& path, const ImageFileSpec& spec,
                                                             std::string& error) = 0;
};

/// OpenImageIO's backend, librfd_imageio.so, loaded on the first call. ImageFileReader and
/// ImageFileWriter use it for every file that core/exr_file.hpp leaves to it.
ImageBackend& imageio_backend();

}  // namespace rfd
