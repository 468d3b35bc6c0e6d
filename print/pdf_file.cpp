#include "print/pdf_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <utility>

#include <cairo-pdf.h>

#include "core/error.hpp"
#include "core/units.hpp"

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

CairoContext page_context(cairo_surface_t* surface) {
    CairoContext cr(cairo_create(surface), &cairo_destroy);
    RFD_CHECK(cairo_status(cr.get()) == CAIRO_STATUS_SUCCESS);
    std::unique_ptr<cairo_font_options_t, decltype(&cairo_font_options_destroy)> options(
        cairo_font_options_create(), &cairo_font_options_destroy);
    cairo_font_options_set_antialias(options.get(), CAIRO_ANTIALIAS_GRAY);
    cairo_font_options_set_hint_style(options.get(), CAIRO_HINT_STYLE_NONE);
    cairo_font_options_set_hint_metrics(options.get(), CAIRO_HINT_METRICS_OFF);
    cairo_set_font_options(cr.get(), options.get());
    return cr;
}

CairoSurface code_row(const std::vector<int>& codes) {
    CairoSurface row(cairo_image_surface_create(CAIRO_FORMAT_RGB24, static_cast<int>(codes.size()), 1),
                     &cairo_surface_destroy);
    cairo_surface_flush(row.get());
    auto* pixels = reinterpret_cast<std::uint32_t*>(cairo_image_surface_get_data(row.get()));
    for (std::size_t k = 0; k < codes.size(); ++k) {
        const auto c = static_cast<std::uint32_t>(codes[k]);
        pixels[k] = (c << 16) | (c << 8) | c;
    }
    cairo_surface_mark_dirty(row.get());
    return row;
}

namespace {

// The page painted over white into an RGB24 surface, `px_per_mm` pixels per mm.
CairoSurface paint_page(double paper_width_mm, double paper_height_mm, double px_per_mm,
                   const std::function<void(cairo_t*)>& draw) {
    const int width = std::max(1, static_cast<int>(std::lround(paper_width_mm * px_per_mm)));
    const int height = std::max(1, static_cast<int>(std::lround(paper_height_mm * px_per_mm)));
    CairoSurface page(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height), &cairo_surface_destroy);
    {
        const CairoContext cr = page_context(page.get());
        cairo_set_source_rgb(cr.get(), 1, 1, 1);
        cairo_paint(cr.get());
        cairo_scale(cr.get(), px_per_mm, px_per_mm);
        draw(cr.get());
    }
    cairo_surface_flush(page.get());
    return page;
}

}  // namespace

Image page_codes(double paper_width_mm, double paper_height_mm, double px_per_mm,
                 const std::function<void(cairo_t*)>& draw) {
    RFD_CHECK(px_per_mm > 0.0);
    const CairoSurface page = paint_page(paper_width_mm, paper_height_mm, px_per_mm, draw);
    const int width = cairo_image_surface_get_width(page.get()), height = cairo_image_surface_get_height(page.get());
    const int stride = cairo_image_surface_get_stride(page.get());
    const unsigned char* data = cairo_image_surface_get_data(page.get());
    Image codes(width, height, 1);
    for (int y = 0; y < height; ++y) {
        const auto* row = reinterpret_cast<const std::uint32_t*>(data + static_cast<std::ptrdiff_t>(y) * stride);
        for (int x = 0; x < width; ++x) codes.at(x, y, 0) = static_cast<float>((row[x] >> 8) & 0xffu) / 255.0f;
    }
    return codes;
}

void write_page_png(const std::filesystem::path& png, double paper_width_mm, double paper_height_mm, int pixels,
                    const std::function<void(cairo_t*)>& draw) {
    const double px_per_mm = pixels / std::max(paper_width_mm, paper_height_mm);
    const CairoSurface page = paint_page(paper_width_mm, paper_height_mm, px_per_mm, draw);
    const std::filesystem::path temporary = temporary_sibling(png);
    if (cairo_surface_write_to_png(page.get(), temporary.c_str()) != CAIRO_STATUS_SUCCESS) {
        remove_temporary(temporary);
        throw IoError(SourceLocation{png.string()}, "cannot write the page's picture");
    }
    move_into_place(temporary, png);
}

void write_pages(const std::filesystem::path& out, const Paper& paper, int pages, const std::string& what,
                 const std::function<void(cairo_t*, int)>& draw, const std::filesystem::path& preview) {
    constexpr double kPointsPerMm = 72.0 / kMillimetresPerInch;
    PdfFile pdf(out, paper.width * kPointsPerMm, paper.height * kPointsPerMm, what);
    {
        const CairoContext cr = page_context(pdf.surface());
        cairo_scale(cr.get(), kPointsPerMm, kPointsPerMm);
        for (int page = 0; page < pages; ++page) {
            draw(cr.get(), page);
            cairo_show_page(cr.get());
        }
    }
    pdf.finish();
    if (!preview.empty()) write_page_png(preview, paper.width, paper.height, kPagePreviewPixels, [&](cairo_t* cr) { draw(cr, 0); });
}

}  // namespace rfd::print
