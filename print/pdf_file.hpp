#pragma once
// A PDF file written through Cairo into a temporary file beside its target, moved into
// place by finish() only when every byte reached the disk: Cairo's stream status, the
// stdio buffer's flush and error flag, the close and (in move_into_place) fsync are all
// checked. Destroyed unfinished, it leaves nothing behind. Dates are fixed, so identical
// drawings give identical files.
//
// Example:
//   PdfFile pdf(out, width_pt, height_pt, "calibration sheet");
//   cairo_t* cr = cairo_create(pdf.surface()); ...draw...; cairo_destroy(cr);
//   pdf.finish();

#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <cairo.h>

#include "core/files.hpp"
#include "core/image.hpp"
#include "print/layout.hpp"
#include "print/printer.hpp"

namespace rfd::print {

class PdfFile {
public:
    /// Throws IoError naming `target` (and `what` it is) when the file cannot be created.
    PdfFile(const std::filesystem::path& target, double width_pt, double height_pt, std::string what);
    ~PdfFile();
    PdfFile(const PdfFile&) = delete;
    PdfFile& operator=(const PdfFile&) = delete;

    cairo_surface_t* surface() { return surface_; }
    /// Finishes the document and moves it into place; throws IoError if any write failed.
    void finish();

private:
    std::filesystem::path target_;
    std::string what_;
    TemporaryFile temporary_;
    std::FILE* file_ = nullptr;
    cairo_surface_t* surface_ = nullptr;
};

using CairoSurface = std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)>;
using CairoContext = std::unique_ptr<cairo_t, decltype(&cairo_destroy)>;

/// A context drawing on `surface` (a PDF's or a picture's) whose text has fixed font options:
/// grey anti-aliasing, no hinting, unhinted metrics. Cairo resolves a font face once per
/// process, with the options of the first surface that draws it, and keeps them for every
/// later one; fixed options make a page's picture the same whatever was drawn before it.
CairoContext page_context(cairo_surface_t* surface);

/// An image one pixel tall holding `codes` (0-255, the same on every channel): exact printer
/// codes for a page to draw without smoothing (CAIRO_FILTER_NEAREST), as sheets draw patterns.
CairoSurface code_row(const std::vector<int>& codes);

/// A page as a screen picture: `draw` paints it (user units: page-frame mm) over white, at
/// `pixels` along the paper's longer side; written as PNG through a temporary file. IoError
/// naming `png` when it cannot be written.
void write_page_png(const std::filesystem::path& png, double paper_width_mm, double paper_height_mm, int pixels,
                    const std::function<void(cairo_t*)>& draw);

/// A page as the printer receives it: `draw` paints it over white at `px_per_mm`, and each
/// pixel holds its code / 255 (1: no ink), one channel (the green one: sheets are grey).
Image page_codes(double paper_width_mm, double paper_height_mm, double px_per_mm,
                 const std::function<void(cairo_t*)>& draw);

/// A PDF of `pages` pages of `paper`, each drawn by `draw(cr, page)` in page-frame mm
/// (`what` names it in messages), and, when `preview` is given, its first page as write_page_png.
void write_pages(const std::filesystem::path& out, const Paper& paper, int pages, const std::string& what,
                 const std::function<void(cairo_t*, int)>& draw, const std::filesystem::path& preview = {});

}  // namespace rfd::print
