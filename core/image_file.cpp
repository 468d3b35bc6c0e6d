#include "core/image_file.hpp"

#include <system_error>

#include "core/error.hpp"
#include "core/exr_file.hpp"
#include "core/exr_header.hpp"
#include "core/files.hpp"
#include "core/image_backend.hpp"
#include "core/image_io.hpp"
#include "core/module.hpp"

namespace rfd {
namespace {

std::size_t row_samples(const ImageFileSpec& spec) {
    return static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.channels);
}

}  // namespace

ImageBackend& imageio_backend() {
    static ImageBackend& loaded = load_module<ImageBackend>("imageio", "rfd_imageio_backend");
    return loaded;
}

std::size_t sample_size(SampleType type) {
    switch (type) {
        case SampleType::UInt8: return 1;
        case SampleType::UInt16:
        case SampleType::Half: return 2;
        case SampleType::Float32: return 4;
    }
    RFD_CHECK(false);
}

const char* sample_type_name(SampleType type) {
    switch (type) {
        case SampleType::UInt8: return "uint8";
        case SampleType::UInt16: return "uint16";
        case SampleType::Half: return "half";
        case SampleType::Float32: return "float";
    }
    RFD_CHECK(false);
}

ImageFileReader::ImageFileReader(const std::filesystem::path& path, const std::string& what)
    : path_(path), what_(what) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw IoError(SourceLocation{path.string()}, "cannot open: no such " + what + " file");
    if (const auto problem = exr_header_problem(path))
        throw InputError(SourceLocation{path.string()}, what + " file is damaged: " + *problem);
    std::string error;
    backend_ = open_exr_file(path.string());
    if (!backend_) backend_ = imageio_backend().open(path.string(), error);
    if (!backend_) throw IoError(SourceLocation{path.string()}, "cannot read " + what + ": " + error);
    spec_ = backend_->spec();
}

ImageFileReader::~ImageFileReader() = default;
ImageFileReader::ImageFileReader(ImageFileReader&&) noexcept = default;
ImageFileReader& ImageFileReader::operator=(ImageFileReader&&) noexcept = default;

void ImageFileReader::read_rows(int y0, int y1, SampleType type, void* out) {
    RFD_CHECK(0 <= y0 && y0 <= y1 && y1 <= spec_.height);
    if (y0 == y1) return;
    if (!backend_->read_rows(y0, y1, type, out))
        throw IoError(SourceLocation{path_.string()}, "cannot read " + what_ + " rows " + std::to_string(y0) + "-" +
                                                          std::to_string(y1) + ": " + backend_->error());
}

void ImageFileReader::read_rows(int y0, int y1, std::span<float> out) {
    RFD_CHECK(out.size() >= row_samples(spec_) * static_cast<std::size_t>(y1 - y0));
    read_rows(y0, y1, SampleType::Float32, out.data());
}

void ImageFileReader::read_rows(int y0, int y1, std::span<std::uint8_t> out) {
    RFD_CHECK(out.size() >= row_samples(spec_) * static_cast<std::size_t>(y1 - y0));
    read_rows(y0, y1, SampleType::UInt8, out.data());
}

ImageFileWriter::ImageFileWriter(const std::filesystem::path& path, const ImageFileSpec& spec, const std::string& what)
    : path_(path), temporary_(temporary_sibling(path)), what_(what), spec_(spec) {
    RFD_CHECK(spec.width > 0 && spec.height > 0 && spec.channels > 0);
    std::string error;
    if (lower_extension(path) == ".exr" && exr_file_covers(spec))
        backend_ = create_exr_file(temporary_.string(), spec, error);
    else
        backend_ = imageio_backend().create(temporary_.string(), spec, error);
    if (!backend_) {
        remove_temporary(temporary_);
        throw IoError(SourceLocation{path.string()}, "cannot write " + what + ": " + error);
    }
}

ImageFileWriter::~ImageFileWriter() {
    if (temporary_.empty()) return;  // finished
    backend_.reset();                // closes the file
    remove_temporary(temporary_);
}

void ImageFileWriter::write_rows(int y0, int y1, SampleType type, const void* rows) {
    RFD_CHECK(!temporary_.empty() && 0 <= y0 && y0 <= y1 && y1 <= spec_.height);
    if (!backend_->write_rows(y0, y1, type, rows))
        throw IoError(SourceLocation{path_.string()}, "cannot write " + what_ + ": " + backend_->error());
}

void ImageFileWriter::write_rows(int y0, int y1, std::span<const float> rows) {
    RFD_CHECK(rows.size() >= row_samples(spec_) * static_cast<std::size_t>(y1 - y0));
    write_rows(y0, y1, SampleType::Float32, rows.data());
}

void ImageFileWriter::finish() {
    RFD_CHECK(!temporary_.empty());
    if (!backend_->close())
        throw IoError(SourceLocation{path_.string()}, "cannot write " + what_ + ": " + backend_->error());
    backend_.reset();
    move_into_place(temporary_, path_);
    temporary_.clear();
}

}  // namespace rfd
