#include "print/sheet.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <vector>

#include <cairo-pdf.h>
#include <cairo.h>

#include "core/error.hpp"
#include "core/number.hpp"
#include "core/files.hpp"
#include "core/image_file.hpp"
#include "core/image_io.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/text.hpp"
#include "print/pdf_file.hpp"
#include "print/printed.hpp"

namespace rfd::print {
namespace {

constexpr int kMaskChunk = 8192;  // columns of one Cairo mask surface (Cairo stops at 32767)

// Printer codes (1 - v, three channels) of one pattern row of `channels` channels.
void tone_row(const float* pattern, int width, int channels, const ToneMap& tone, float* codes) {
    for (int x = 0; x < width; ++x)
        for (int c = 0; c < 3; ++c) {
            const float p = pattern[static_cast<std::size_t>(x) * static_cast<std::size_t>(channels) +
                                    static_cast<std::size_t>(channels == 1 ? 0 : c)];
            codes[3 * static_cast<std::size_t>(x) + static_cast<std::size_t>(c)] =
                static_cast<float>(1.0 - tone.printer_value(p));
        }
}

// Renders the clear and ink masks of page rows [y0, y0 + rows) with Cairo, in column chunks.
class MaskRenderer {
public:
    MaskRenderer(const SheetLayout& layout, int rows)
        : layout_(layout), rows_(rows),
          clear_(static_cast<std::size_t>(layout.page_width) * static_cast<std::size_t>(rows)),
          ink_(clear_.size()) {}

    void render(int y0) {
        std::fill(clear_.begin(), clear_.end(), 0);
        std::fill(ink_.begin(), ink_.end(), 0);
        for (int x0 = 0; x0 < layout_.page_width; x0 += kMaskChunk) {
            const int width = std::min(kMaskChunk, layout_.page_width - x0);
            render_chunk(x0, y0, width, /*clear=*/true);
            render_chunk(x0, y0, width, /*clear=*/false);
        }
    }
    /// Coverage in [0, 255] of page dot (x, y0 + r).
    std::uint8_t clear(int x, int r) const { return clear_[index(x, r)]; }
    std::uint8_t ink(int x, int r) const { return ink_[index(x, r)]; }

private:
    std::size_t index(int x, int r) const {
        return static_cast<std::size_t>(r) * static_cast<std::size_t>(layout_.page_width) +
               static_cast<std::size_t>(x);
    }
    void render_chunk(int x0, int y0, int width, bool clear) {
        CairoSurface surface(cairo_image_surface_create(CAIRO_FORMAT_A8, width, rows_), &cairo_surface_destroy);
        const CairoContext cr = page_context(surface.get());
        // User units: page-frame mm; device: dots of this chunk.
        cairo_matrix_t m;
        cairo_matrix_init(&m, 1.0 / layout_.dot_x, 0.0, 0.0, 1.0 / layout_.dot_y, -x0, -y0);
        cairo_set_matrix(cr.get(), &m);
        cairo_set_source_rgba(cr.get(), 0, 0, 0, 1);
        if (clear) {
            trace_clear_regions(cr.get(), layout_);
            cairo_fill(cr.get());
        } else {
            draw_marks(cr.get(), layout_);
        }
        cairo_surface_flush(surface.get());
        const unsigned char* data = cairo_image_surface_get_data(surface.get());
        const int stride = cairo_image_surface_get_stride(surface.get());
        std::vector<std::uint8_t>& target = clear ? clear_ : ink_;
        for (int r = 0; r < rows_; ++r)
            std::copy(data + static_cast<std::ptrdiff_t>(r) * stride, data + static_cast<std::ptrdiff_t>(r) * stride + width,
                      target.begin() + static_cast<std::ptrdiff_t>(index(x0, r)));
    }

    const SheetLayout& layout_;
    int rows_;
    std::vector<std::uint8_t> clear_, ink_;
};

void write_tiff(const std::filesystem::path& out, const SheetLayout& layout, const ToneMap& tone,
                patterns::PatternReader& reader, const SheetOptions& options) {
    const int W = layout.page_width, H = layout.page_height;
    const int channels = reader.info().channels;
    const patterns::PatternGeometry& g = layout.pattern;
    ImageFileSpec spec{.width = W, .height = H, .channels = 3,
                       .type = options.bits == 16 ? SampleType::UInt16 : SampleType::UInt8,
                       .dpi_x = layout.dpi_x, .dpi_y = layout.dpi_y, .compression = "zip"};
    for (const std::string& line : layout.label) spec.description += line + "\n";
    ImageFileWriter output(out, spec, "sheet");

    const int strip = std::max(1, std::min(options.rows_per_strip, H));
    const std::size_t row_codes = 3 * static_cast<std::size_t>(W);
    std::vector<float> pattern_rows(static_cast<std::size_t>(g.width) * static_cast<std::size_t>(channels) *
                                    static_cast<std::size_t>(strip));
    std::vector<float> codes(row_codes * static_cast<std::size_t>(strip));
    MaskRenderer masks(layout, strip);
    // Copies of one row share page rows; a strip never spans two rows of copies, so that it
    // needs one range of pattern rows.
    std::vector<int> row_tops;  // page row of each row of copies' first pattern row
    for (const Eigen::Vector2i& copy : layout.copies)
        if (row_tops.empty() || layout.offset_y + copy.y() != row_tops.back()) row_tops.push_back(layout.offset_y + copy.y());
    std::vector<int> breaks;
    for (const int top : row_tops) breaks.insert(breaks.end(), {top, top + g.height});
    Progress progress("sheet rows", static_cast<std::size_t>(H));
    for (int y0 = 0, y1 = 0; y0 < H; y0 = y1) {
        y1 = std::min(H, y0 + strip);
        for (const int b : breaks)
            if (b > y0 && b < y1) y1 = b;
        // The row of copies this strip crosses, if any, and its pattern rows.
        int top = 0;
        bool inside = false;
        for (const int t : row_tops)
            if (y0 >= t && y0 < t + g.height) {
                top = t;
                inside = true;
            }
        const int p0 = inside ? y0 - top : 0, p1 = inside ? y1 - top : 0;
        if (inside) reader.read_rows(p0, p1, pattern_rows);
        masks.render(y0);
        parallel_for_chunks(static_cast<std::size_t>(y1 - y0), 1, [&](std::size_t begin, std::size_t end) {
            std::vector<float> front(row_codes);
            for (std::size_t r = begin; r < end; ++r) {
                const int y = y0 + static_cast<int>(r);
                std::fill(front.begin(), front.end(), 1.0f);  // bare film
                if (inside) {
                    float* first = front.data() + 3 * static_cast<std::size_t>(layout.offset_x);
                    tone_row(pattern_rows.data() + static_cast<std::size_t>(y - top - p0) *
                                                       static_cast<std::size_t>(g.width) *
                                                       static_cast<std::size_t>(channels),
                             g.width, channels, tone, first);
                    for (const Eigen::Vector2i& copy : layout.copies)
                        if (copy.x() != 0 && layout.offset_y + copy.y() == top)
                            std::copy(first, first + 3 * static_cast<std::size_t>(g.width),
                                      first + 3 * static_cast<std::ptrdiff_t>(copy.x()));
                }
                for (int x = 0; x < W; ++x) {
                    const float clear = masks.clear(x, static_cast<int>(r)) / 255.0f;
                    const float ink = masks.ink(x, static_cast<int>(r)) / 255.0f;
                    float* code = front.data() + 3 * static_cast<std::size_t>(x);
                    for (int c = 0; c < 3; ++c) {
                        float v = 1.0f - code[c];
                        v *= 1.0f - clear;
                        v += (1.0f - v) * ink;
                        code[c] = 1.0f - v;
                    }
                }
                float* row = codes.data() + r * row_codes;
                for (int x = 0; x < W; ++x) {
                    const int source = layout.mirror ? W - 1 - x : x;
                    for (int c = 0; c < 3; ++c)
                        row[3 * static_cast<std::size_t>(x) + static_cast<std::size_t>(c)] =
                            front[3 * static_cast<std::size_t>(source) + static_cast<std::size_t>(c)];
                }
            }
        });
        output.write_rows(y0, y1, codes);
        progress.advance(static_cast<std::size_t>(y1 - y0));
    }
    output.finish();
    progress.finish();
}

void write_pdf(const std::filesystem::path& out, const SheetLayout& layout, const ToneMap& tone,
               patterns::PatternReader& reader) {
    constexpr double kPointsPerMm = 72.0 / kMillimetresPerInch;
    const int channels = reader.info().channels;
    const patterns::PatternGeometry& g = layout.pattern;
    PdfFile pdf(out, layout.paper.width * kPointsPerMm, layout.paper.height * kPointsPerMm, "sheet");
    {
        cairo_pdf_surface_set_metadata(pdf.surface(), CAIRO_PDF_METADATA_TITLE, layout.label.front().c_str());
        const CairoContext cr = page_context(pdf.surface());
        cairo_scale(cr.get(), kPointsPerMm, kPointsPerMm);  // user units: page-frame mm
        if (layout.mirror) {
            cairo_translate(cr.get(), layout.paper.width, 0.0);
            cairo_scale(cr.get(), -1.0, 1.0);
        }
        // The pattern, a band of tiles at a time; each tile its own image at the true dot size.
        // A viewer that anti-aliases image edges blends two abutting tiles with the paper
        // where they meet, a light line, so tiles overlap: each carries the next tile's first
        // dots (the same data) and is drawn first, and the next one, drawn over it, starts at
        // its true dot. No clip path: the images' edges are their own, on whole dots.
        const int overlap_x = pdf_tile_overlap(layout.dpi_x), overlap_y = pdf_tile_overlap(layout.dpi_y);
        const std::size_t row_floats = static_cast<std::size_t>(g.width) * static_cast<std::size_t>(channels);
        constexpr int kReadRows = 64;
        std::vector<float> rows(row_floats * kReadRows);
        std::vector<float> codes(3 * static_cast<std::size_t>(g.width));
        Progress progress("sheet rows", static_cast<std::size_t>(g.height));
        for (int ty = 0; ty < g.height; ty += kPdfTile) {
            const int th = std::min(kPdfTile + overlap_y, g.height - ty);  // rows with the overlap
            std::vector<CairoSurface> tiles;
            std::vector<int> tile_x;
            for (int tx = 0; tx < g.width; tx += kPdfTile) {
                tiles.emplace_back(cairo_image_surface_create(CAIRO_FORMAT_RGB24, std::min(kPdfTile + overlap_x, g.width - tx), th),
                                   &cairo_surface_destroy);
                tile_x.push_back(tx);
            }
            for (int r0 = 0; r0 < th; r0 += kReadRows) {
                const int r1 = std::min(th, r0 + kReadRows);
                reader.read_rows(ty + r0, ty + r1, rows);
                for (int r = r0; r < r1; ++r) {
                    tone_row(rows.data() + static_cast<std::size_t>(r - r0) * row_floats, g.width, channels, tone,
                             codes.data());
                    for (std::size_t t = 0; t < tiles.size(); ++t) {
                        cairo_surface_t* tile = tiles[t].get();
                        auto* pixels = reinterpret_cast<std::uint32_t*>(
                            cairo_image_surface_get_data(tile) +
                            static_cast<std::ptrdiff_t>(r) * cairo_image_surface_get_stride(tile));
                        const int x0 = tile_x[t];
                        for (int x = 0; x < cairo_image_surface_get_width(tile); ++x) {
                            std::uint32_t pixel = 0;
                            for (int c = 0; c < 3; ++c)
                                pixel = pixel << 8 |
                                        static_cast<std::uint32_t>(std::lround(
                                            255.0f * codes[3 * static_cast<std::size_t>(x0 + x) + static_cast<std::size_t>(c)]));
                            pixels[x] = pixel;
                        }
                    }
                }
                // Rows of the overlap are the next band's and counted there.
                progress.advance(static_cast<std::size_t>(std::max(0, std::min(r1, kPdfTile) - std::min(r0, kPdfTile))));
            }
            for (std::size_t t = 0; t < tiles.size(); ++t) {
                cairo_surface_mark_dirty(tiles[t].get());
                for (const Eigen::Vector2i& copy : layout.copies) {
                    cairo_save(cr.get());
                    cairo_translate(cr.get(), (layout.offset_x + copy.x() + tile_x[t]) * layout.dot_x,
                                    (layout.offset_y + copy.y() + ty) * layout.dot_y);
                    cairo_scale(cr.get(), layout.dot_x, layout.dot_y);
                    cairo_set_source_surface(cr.get(), tiles[t].get(), 0.0, 0.0);
                    cairo_pattern_set_filter(cairo_get_source(cr.get()), CAIRO_FILTER_NEAREST);
                    cairo_paint(cr.get());
                    cairo_restore(cr.get());
                }
            }
        }
        progress.finish();
        cairo_set_source_rgb(cr.get(), 1, 1, 1);
        trace_clear_regions(cr.get(), layout);
        cairo_fill(cr.get());
        cairo_set_source_rgb(cr.get(), 0, 0, 0);
        draw_marks(cr.get(), layout);
        cairo_show_page(cr.get());
    }
    pdf.finish();
}

// The page at kPagePreviewPixels along its longer side, as write_pdf draws it.
void write_preview(const std::filesystem::path& png, const SheetLayout& layout, const ToneMap& tone,
                   const std::filesystem::path& pattern_file) {
    const double px_per_mm = kPagePreviewPixels / std::max(layout.paper.width, layout.paper.height);
    const Eigen::Vector2d lo = layout.pattern_min(), hi = layout.pattern_max();
    // No picture pixel smaller than a dot, so that every one averages at least one; Cairo
    // scales the picture onto the page.
    const int pw = std::clamp(static_cast<int>(std::lround((hi.x() - lo.x()) * px_per_mm)), 1, layout.pattern.width);
    const int ph = std::clamp(static_cast<int>(std::lround((hi.y() - lo.y()) * px_per_mm)), 1, layout.pattern.height);
    const Image pattern = patterns::box_averaged(pattern_file, pw, ph);

    CairoSurface picture(cairo_image_surface_create(CAIRO_FORMAT_RGB24, pw, ph), &cairo_surface_destroy);
    cairo_surface_flush(picture.get());
    std::vector<float> values(static_cast<std::size_t>(pw) * static_cast<std::size_t>(pattern.channels()));
    std::vector<float> codes(3 * static_cast<std::size_t>(pw));
    for (int y = 0; y < ph; ++y) {
        for (int x = 0; x < pw; ++x)
            for (int c = 0; c < pattern.channels(); ++c)
                values[static_cast<std::size_t>(x * pattern.channels() + c)] = pattern.at(x, y, c);
        tone_row(values.data(), pw, pattern.channels(), tone, codes.data());
        auto* row = reinterpret_cast<std::uint32_t*>(cairo_image_surface_get_data(picture.get()) +
                                                     static_cast<std::ptrdiff_t>(y) * cairo_image_surface_get_stride(picture.get()));
        for (int x = 0; x < pw; ++x) {
            std::uint32_t pixel = 0;
            for (int c = 0; c < 3; ++c)
                pixel = pixel << 8 | static_cast<std::uint32_t>(std::lround(255.0f * codes[3 * static_cast<std::size_t>(x) + c]));
            row[x] = pixel;
        }
    }
    cairo_surface_mark_dirty(picture.get());

    write_page_png(png, layout.paper.width, layout.paper.height, kPagePreviewPixels, [&](cairo_t* cr) {
        if (layout.mirror) {
            cairo_translate(cr, layout.paper.width, 0.0);
            cairo_scale(cr, -1.0, 1.0);
        }
        for (std::size_t copy = 0; copy < layout.copies.size(); ++copy) {
            const Eigen::Vector2d shift = layout.copy_mm(copy);
            cairo_save(cr);
            cairo_translate(cr, lo.x() + shift.x(), lo.y() + shift.y());
            cairo_scale(cr, (hi.x() - lo.x()) / pw, (hi.y() - lo.y()) / ph);
            cairo_set_source_surface(cr, picture.get(), 0.0, 0.0);
            cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
            cairo_paint(cr);
            cairo_restore(cr);
        }
        cairo_set_source_rgb(cr, 1, 1, 1);
        trace_clear_regions(cr, layout);
        cairo_fill(cr);
        cairo_set_source_rgb(cr, 0, 0, 0);
        draw_marks(cr, layout);
    });
}

}  // namespace

SheetReport write_sheet(const std::filesystem::path& out, const optics::Design& design,
                        const PrinterProfile& printer, const std::filesystem::path& pattern_file,
                        const SheetOptions& options) {
    const std::string ext = lower_extension(out);
    const bool pdf = ext == ".pdf";
    if (!pdf && ext != ".tif" && ext != ".tiff")
        throw InputError(SourceLocation{out.string(), 0, 0, "--out"},
                         "unknown sheet extension '" + ext + "' (expected .tif, .tiff or .pdf)");
    check_tone_options(options.brightness, options.sheets);
    if (options.bits != 8 && options.bits != 16)
        throw InputError(SourceLocation{"", 0, 0, "--bits"}, "expected 8 or 16, got " + std::to_string(options.bits));
    const int sheets = options.sheets == 0 ? printer.sheets : options.sheets;
    // A mirrored page is the back sheet of a stack of two; alone it would show the pattern
    // flipped.
    if (options.mirror && sheets != 2)
        throw InputError(SourceLocation{"", 0, 0, "--mirror"},
                         "a mirrored page is the back sheet of two, but this print has one sheet (" +
                             (options.sheets == 0 ? "printer profile '" + printer.name + "'" : std::string("--sheets 1")) +
                             "): print the front sheet alone, or give --sheets 2");
    patterns::PatternReader reader(pattern_file);
    const PrintSetup setup = check_print(design, printer, pattern_file, reader.info(), options.brightness, sheets);
    const patterns::PatternGeometry& geometry = setup.geometry;

    SheetReport report;
    report.pattern_channels = setup.channels;
    report.tone = setup.tone;
    SheetInfo info;
    info.pattern_name = pattern_file.filename().string();
    info.brightness = options.brightness;
    info.sheets = report.tone.sheets;
    info.mirror = options.mirror;
    info.copies = options.copies;
    report.layout = layout_sheet(design, printer, geometry, info);
    if (!options.preview.empty() && lower_extension(options.preview) != ".png")
        throw InputError(SourceLocation{options.preview.string(), 0, 0, "--preview"}, "expected a .png file");
    if (pdf)
        write_pdf(out, report.layout, report.tone, reader);
    else
        write_tiff(out, report.layout, report.tone, reader, options);
    if (!options.preview.empty()) write_preview(options.preview, report.layout, report.tone, pattern_file);
    return report;
}

}  // namespace rfd::print
