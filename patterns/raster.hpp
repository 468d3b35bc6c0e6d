#pragma once
// Pattern rasters: where the printer dots of a pattern lie on a design, and how a pattern of
// hundreds of millions of dots is written to disk in bounded memory.
//
// Raster frame: dot (px, py), px to the right and py down, as the observer sees the pattern
// (looking at the display's front, along -z; docs/formats.md). Row 0 is the top row of the
// file. Dot centres in the lattice frame of the encoding plane (optics/lattice.hpp: x right,
// y up, origin at the array's centre, millimetres) are
//     x = (px + 0.5 - width / 2) * dot_x,    y = (height / 2 - py - 0.5) * dot_y,
// so the raster's centre is the array's centre. The raster covers the array's outer cell
// boundaries plus a margin on every side, rounded up to whole dots.
//
// Example: PatternGeometry g = pattern_geometry(design, Dpi{2880}, Dpi{1440});
//          Eigen::Vector2d mm = g.dot_centre(100, 200);

#include <cstddef>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>

#include <Eigen/Core>

#include "core/options.hpp"
#include "core/image.hpp"
#include "core/image_file.hpp"
#include "core/units.hpp"
#include "optics/design.hpp"

namespace rfd::patterns {

struct PatternGeometry {
    int width = 0;        ///< dots along x
    int height = 0;       ///< dots along y
    double dot_x = 0.0;   ///< mm per dot along x (25.4 / dpi_x)
    double dot_y = 0.0;   ///< mm per dot along y
    double dpi_x = 0.0;
    double dpi_y = 0.0;
    double margin_mm = 0.0;  ///< blank border around the array on every side

    std::size_t dot_count() const {
        return static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    }
    /// Centre of dot (px, py) in the lattice frame, mm.
    Eigen::Vector2d dot_centre(double px, double py) const {
        return {(px + 0.5 - 0.5 * width) * dot_x, (0.5 * height - py - 0.5) * dot_y};
    }
    /// Continuous raster coordinates (dot centres at integers) of a lattice-frame point.
    Eigen::Vector2d raster_position(const Eigen::Vector2d& mm) const {
        return {mm.x() / dot_x + 0.5 * width - 0.5, 0.5 * height - mm.y() / dot_y - 0.5};
    }
    /// Physical size of the raster, mm.
    Eigen::Vector2d size_mm() const { return {width * dot_x, height * dot_y}; }
};

/// The raster of `design`'s pattern plane at the given resolution, with `margin_mm` of blank
/// border on every side: the extent of the pattern plane's lenslet array (Designs I-III) or
/// of the macro-pixel grid (IV). Throws InputError when a resolution is not positive or the
/// raster would exceed 2^31 - 1 dots along a side.
inline constexpr NumberOption kMarginOption{"--margin", "margin_mm", "mm", 0.0, 100.0, 0.0,
                                            "Blank border around the array"};
PatternGeometry pattern_geometry(const optics::Design& design, Dpi dpi_x, Dpi dpi_y,
                                 double margin_mm = kMarginOption.fallback);

/// Any pattern that can produce its rows on demand. Implementations must be thread-safe:
/// render_row is called concurrently for different rows.
class PatternSource {
public:
    virtual ~PatternSource() = default;
    virtual const PatternGeometry& geometry() const = 0;
    virtual int channels() const = 0;
    /// Writes row `py`, interleaved (width * channels floats, channel fastest), to `out`.
    /// Values are linear; they must be finite.
    virtual void render_row(int py, std::span<float> out) const = 0;
};

/// Key/value metadata stored with a pattern file ("rfd:" attributes in its header):
/// the design, the encoding options, the reference white the print step scales to.
using PatternAttributes = std::map<std::string, std::string>;

struct WriteOptions {
    int rows_per_strip = 64;        ///< rows rendered in parallel and written at once
    bool half_float = true;         ///< EXR: 16-bit half floats (relative error 5e-4)
    std::string exr_compression = "rle";  ///< EXR, lossless: none, rle (cheap), zips/zip (4x smaller, 3x the CPU), piz
    std::string progress_label = "pattern rows";
};

/// Throws InputError at `where` unless `channels` is 1 (grey) or 3 (R, G, B): what a
/// transparency is printed in, and all a print sheet takes.
void require_printable_channels(int channels, const SourceLocation& where);

/// Streams `source` into `path` (EXR for linear float; TIFF/PNG through write_image's
/// encodings), a strip of rows at a time rendered in parallel, so memory stays at a few
/// strips whatever the raster's size. The resolution (dpi on both axes) and `attributes`
/// go into the header. Written to a temporary sibling and renamed: an interrupted or failed
/// write leaves nothing at `path`. Throws IoError when the file cannot be written and
/// InputError when a rendered sample is not finite (naming the dot) or the source's
/// channels are not printable.
void write_pattern(const std::filesystem::path& path, const PatternSource& source,
                   const PatternAttributes& attributes, const WriteOptions& options = {});

/// What a pattern file says about itself.
struct PatternFileInfo {
    int width = 0, height = 0, channels = 0;
    double dpi_x = 0.0, dpi_y = 0.0;   ///< 0 when the file has no resolution
    PatternAttributes attributes;      ///< the "rfd:" attributes, without the prefix
};
PatternFileInfo read_pattern_info(const std::filesystem::path& path);

/// The number in rfd: attribute `key`, or `fallback` when the file has none. InputError
/// naming `file` and the attribute when it is not one finite number in `range`.
enum class NumberRange { Any, NonNegative, Positive };
double number_attribute(const PatternFileInfo& info, const std::string& key, const std::filesystem::path& file,
                        double fallback, NumberRange range = NumberRange::Any);

/// Reads an image file a strip of rows at a time, for files too large to load: linear
/// floats, interleaved, integer formats decoded from sRGB as read_image does, alpha dropped.
/// Throws IoError naming the file when it cannot be opened or read, InputError for a
/// non-finite sample.
class PatternReader {
public:
    explicit PatternReader(const std::filesystem::path& path);
    ~PatternReader();
    PatternReader(PatternReader&&) noexcept;
    PatternReader& operator=(PatternReader&&) noexcept;
    const PatternFileInfo& info() const { return info_; }
    /// Rows [y0, y1), width * channels floats each, into `out`.
    void read_rows(int y0, int y1, std::span<float> out);

private:
    std::unique_ptr<ImageFileReader> file_;
    PatternFileInfo info_;
};

/// The pattern file's values box-averaged down to `width` x `height` pixels (each pixel the
/// mean of the dots whose index maps into it), streamed strip by strip.
Image box_averaged(const std::filesystem::path& pattern, int width, int height);

/// A small preview of a pattern file for screens: box-averaged down to at most `max_side`
/// pixels along its longer side (non-square dots averaged to square pixels), divided by
/// `white` (the pattern's rfd:white when 0) and written through write_image (PNG: sRGB).
/// Streams the pattern strip by strip.
void write_preview(const std::filesystem::path& pattern, const std::filesystem::path& preview, int max_side,
                   double white = 0.0);

}  // namespace rfd::patterns
