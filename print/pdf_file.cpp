#include "print/pdf_file.hpp"

#include <utility>

#include <cairo-pdf.h>

#include "core/error.hpp"

namespace rfd::print {
namespace {

cairo_status_t write_to_file(void* closure, const unsigned char* data, unsigned int length) {
    auto* file = static_cast<std::FILE*>(closure);
    return std::fwrite(data, 1, length, file) == length ? CAIRO_STATUS_SUCCESS : CAIRO_STATUS_WRITE_ERROR;
}

}  // namespace

PdfFile::PdfFile(const std::filesystem::path& target, double width_pt, double height_pt, std::string what)
    : target_(target), what_(std::move(what)), temporary_(temporary_sibling(target)) {
    file_ = std::fopen(temporary_.path().c_str(), "wb");
    if (!file_) throw IoError(SourceLocation{target_.string()}, "cannot write " + what_ + ": cannot create a file there");
    surface_ = cairo_pdf_surface_create_for_stream(write_to_file, file_, width_pt, height_pt);
    cairo_pdf_surface_set_metadata(surface_, CAIRO_PDF_METADATA_CREATE_DATE, "1970-01-01T00:00:00Z");
    cairo_pdf_surface_set_metadata(surface_, CAIRO_PDF_METADATA_MOD_DATE, "1970-01-01T00:00:00Z");
}

PdfFile::~PdfFile() {
    if (surface_) cairo_surface_destroy(surface_);
    if (file_) std::fclose(file_);
}

void PdfFile::finish() {
    cairo_surface_finish(surface_);
    const cairo_status_t status = cairo_surface_status(surface_);
    cairo_surface_destroy(surface_);
    surface_ = nullptr;
    const auto fail = [&](const std::string& why) {
        throw IoError(SourceLocation{target_.string()}, "cannot write " + what_ + ": " + why);
    };
    if (status != CAIRO_STATUS_SUCCESS) fail(cairo_status_to_string(status));
    if (std::fflush(file_) != 0 || std::ferror(file_)) fail("writing failed (disk full?)");
    std::FILE* file = std::exchange(file_, nullptr);
    if (std::fclose(file) != 0) fail("closing the file failed");
    move_into_place(temporary_.path(), target_);
    temporary_.release();
}

}  // namespace rfd::print
