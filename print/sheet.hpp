#pragma once
// Printed sheets (thesis 8.4, 8.4.1): a pattern file, tone-mapped for a printer, on its
// page with registration markers, crop marks, ruler and label (layout.hpp), written as
//  - TIFF: the whole page at the printer's resolution, RGB, 8 or 16 bits per channel,
//    zip-compressed, streamed a strip of rows at a time (memory stays at a few strips
//    whatever the page's size), XResolution/YResolution = the printer's dpi; the codes are
//    the printer's codes 1 - v (printer.hpp), not sRGB-encoded light;
//  - PDF: a page of the paper's exact size (points = mm / 25.4 * 72), the pattern as
//    tiles of kPdfTile x kPdfTile dots each at the true dot size (x and y scaled
//    separately), drawn with nearest-neighbour filtering, each carrying the next tile's
//    first dots (the same dots, pdf_tile_overlap()) under it, so that viewers which
//    anti-alias image edges show no line where tiles meet; the marks as vectors. Cairo's PDF writer keeps the page's images until the page is finished,
//    so a PDF needs memory for the whole raster (4 bytes a dot): use TIFF for full-page
//    patterns at 2880 x 1440 dpi.
// Both are written to a temporary sibling and renamed: nothing half-written survives a
// failure. Identical inputs give byte-identical files (no time stamps).
//
// --mirror writes the back sheet: the whole page mirrored left-right, so that when the
// sheet is flipped and laid behind the front its markers fall on the same lenslets.
//
// Example: write_sheet("sheet.tif", design, printer, "pattern.tif", {.brightness = 1.2});

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "optics/design.hpp"
#include "print/layout.hpp"
#include "print/printed.hpp"
#include "print/printer.hpp"

namespace rfd::print {

inline constexpr int kPdfTile = 2048;  ///< PDF image tile pitch, dots (Cairo stops at 32767)
/// How far (inches) a PDF tile reaches under the next: one pixel of a viewer at 32 dpi, so
/// that the anti-aliased edge of the tile on top lies over the same picture, not the paper.
inline constexpr double kPdfTileOverlapInch = 1.0 / 32.0;
/// Dots a PDF tile reaches under the next at `dpi` along that axis: kPdfTileOverlapInch,
/// at most an eighth of a tile.
inline int pdf_tile_overlap(double dpi) {
    return std::min(kPdfTile / 8, static_cast<int>(std::ceil(dpi * kPdfTileOverlapInch)));
}

struct SheetOptions {
    double brightness = kBrightnessOption.fallback;  ///< scales the pattern before clamping, > 0
    int sheets = static_cast<int>(kSheetsOption.fallback);  ///< 1 or 2; 0 takes the printer profile's default
    bool mirror = false;      ///< the mirrored back sheet
    int bits = 8;             ///< TIFF bits per channel, 8 or 16
    int rows_per_strip = 64;  ///< TIFF rows composed at once
    int copies = 1;           ///< copies of the pattern on the page; 0: as many as fit
    std::filesystem::path preview;  ///< also a small PNG of the page here, when not empty
};


/// What write_sheet did, for the command's report.
struct SheetReport {
    SheetLayout layout;
    ToneMap tone;
    int pattern_channels = 0;
};

/// Writes the sheet; the format follows `out`'s extension (.tif/.tiff or .pdf). With
/// options.preview, also the page as a screen sees it, kPagePreviewPixels (layout.hpp) along its longer
/// side: the pattern box-averaged and tone-mapped as printed, the marks drawn (PNG). Throws
/// InputError for bad options, a pattern that does not match the design at the printer's
/// dpi or does not fit the paper, IoError when a file cannot be read or written.
SheetReport write_sheet(const std::filesystem::path& out, const optics::Design& design,
                        const PrinterProfile& printer, const std::filesystem::path& pattern_file,
                        const SheetOptions& options);

}  // namespace rfd::print
