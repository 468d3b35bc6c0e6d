#pragma once
// A pattern as the printer will print it, for the display simulator: each dot's
// transmittance after the tone mapping of printer.hpp (brightness, white, gamma, black
// level, maximum density, sheets stacked back to back), read from the pattern file.
//
// The file is not loaded: sample() sorts the points by row and reads only the rows they
// land in (consecutive ones as one strip), so a full-page pattern costs a strip of memory.
//
// Example: PrintedTransparency t(design, load_printer("epson_stylus_pro_4800"), "p.exr", 1.0, 0);
//          DiffuserImage out = DisplaySimulator(design).simulate(t, lights, {});

#include <filesystem>
#include <optional>
#include <string>

#include "core/options.hpp"
#include "optics/design.hpp"
#include "optics/display.hpp"
#include "patterns/raster.hpp"
#include "print/layout.hpp"
#include "print/printer.hpp"

namespace rfd::print {

/// Checks that `pattern_file` is `design`'s raster at the printer's dpi (size and, when the
/// file has one, resolution; with the file's rfd:margin_mm if any) and returns that raster.
/// Throws InputError naming the file and both sizes otherwise.
patterns::PatternGeometry check_pattern(const optics::Design& design, const PrinterProfile& printer,
                                        const std::filesystem::path& pattern_file,
                                        const patterns::PatternFileInfo& info);

/// The attributes that record in a pattern the printer it is encoded for: rfd:printer (the
/// profile's name, for people) and rfd:printer_profile (printer_toml, the whole profile).
patterns::PatternAttributes printer_attributes(const PrinterProfile& printer);

/// The profile a pattern records (printer_attributes), if any; InputError naming the file
/// and attribute when the record is damaged.
std::optional<PrinterProfile> recorded_printer(const patterns::PatternFileInfo& info,
                                               const std::filesystem::path& pattern_file);

/// The printer that prints (and, for the simulator, has printed) `pattern_file`:
///  - `requested` (a --printer value: a file or a bundled name) when given; InputError
///    naming both profiles when the pattern records another one;
///  - otherwise the profile the pattern records;
///  - otherwise default_printer at the resolution the file records, or at the design's.
/// The requested profile is read before the pattern, so a bad --printer is reported first.
PrinterProfile printer_for_pattern(const optics::Design& design, const std::filesystem::path& pattern_file,
                                   const std::string& requested);

/// How a pattern is printed, every command's that prints or predicts one.
inline constexpr NumberOption kBrightnessOption{"--brightness", "", "", 1e-6, 1e6, 1.0,
                                                "Tone mapping: transmittance = brightness * value / white"};
inline constexpr IntegerOption kSheetsOption{"--sheets", "", "", 0, 2, 0,
                                             "Sheets stacked back to back (2 prints each at the square root); 0: the "
                                             "printer profile's"};

/// --brightness (positive, finite) and --sheets (1, 2, or 0 for the profile's): InputError
/// naming the option otherwise.
void check_tone_options(double brightness, int sheets);

/// A pattern file as it will be printed: its raster (check_pattern), channels (1 or 3)
/// and tone mapping (the printer's, the file's rfd:white, `brightness`, `sheets`; 0 sheets
/// means the profile's).
struct PrintSetup {
    patterns::PatternGeometry geometry;
    ToneMap tone;
    int channels = 0;
};
PrintSetup check_print(const optics::Design& design, const PrinterProfile& printer,
                       const std::filesystem::path& pattern_file, const patterns::PatternFileInfo& info,
                       double brightness, int sheets);

class PrintedTransparency final : public optics::Transparency {
public:
    /// Checks the pattern against the design at the printer's dpi (check_pattern: size and
    /// resolution) and its channels (1 or 3); InputError naming the file otherwise.
    /// `sheets` 0 means the printer profile's.
    PrintedTransparency(const optics::Design& design, const PrinterProfile& printer,
                        std::filesystem::path pattern_file, double brightness, int sheets);

    int channels() const override { return channels_; }
    /// Thread-safe: every call opens its own reader.
    void sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const override;

    const ToneMap& tone() const { return tone_; }
    const patterns::PatternGeometry& geometry() const { return geometry_; }

private:
    std::filesystem::path file_;
    patterns::PatternGeometry geometry_;
    ToneMap tone_;
    int channels_ = 0;
};

/// A pattern as its printed sheet carries it (layout.hpp): the corner lenslets' cells clear
/// (transmittance 1), the markers' ring and crosshair in full ink on every sheet of the stack,
/// the rest `pattern`'s. What a photograph of the assembled display sees: the marker cells
/// lit wherever the light's spot misses the ink. Keeps a reference: `pattern` must outlive it.
class MarkedTransparency final : public optics::Transparency {
public:
    MarkedTransparency(const optics::Transparency& pattern, const optics::Design& design, const ToneMap& tone);
    int channels() const override { return pattern_.channels(); }
    void sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const override;

private:
    const optics::Transparency& pattern_;
    std::vector<MarkerShape> markers_;
    std::vector<double> reach2_;  // squared distance from each marker's centre to its cell's farthest corner
    float ink_ = 0.0f;            // the stack's transmittance under full ink
};

}  // namespace rfd::print
