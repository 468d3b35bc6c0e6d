#pragma once
// Printer profiles (printers/*.toml, docs/formats.md) and the tone mapping of thesis 8.4:
// "scaling [the pattern's] intensity linearly to a comfortable brightness and performing a
// gamma and blacklevel correction for the output device", with two sheets back to back
// for contrast.
//
// Printer model. A printer value v in [0, 1] is the amount of ink asked for (0: bare
// film, 1: full ink); a sheet file stores the code c = 1 - v per channel (white = no ink),
// the number the printer driver receives. Full ink has optical density D = max_density,
// transmittance T_ink = 10^-D, and the driver's transfer from code to transmittance is a
// power law between bare film and full ink:
//     T(v) = T_ink + (1 - T_ink) * (1 - v)^gamma,     v = 1 - ((T - T_ink) / (1 - T_ink))^(1/gamma).
// gamma is about 2.2 for a driver that treats files as sRGB, 1 for a linearised RIP;
// measure it by printing a step wedge. black_level is the transmittance a sheet's darkest
// dot aims for (>= T_ink, a little above it for head room against ink variation).
//
// A measured curve (`rfd calibrate tone`) replaces the power law: a [tone] table of
// transmittances at increasing ink values from 0 to 1, read piecewise linearly in density
// (log T) between them, so that dark steps keep their relative precision. T(0) = 1 by
// definition, and T(1) = T_ink.
//
// Tone mapping of a pattern value p (linear, rfd:white = the value meant as full
// transmittance) for a stack of n sheets printed identically (n = 2: the front sheet and
// its mirror, mounted back to back, so the stack transmits the product):
//     t     = clamp(brightness * p / white, 0, 1)      desired transmittance of the stack
//     t'    = b^n + (1 - b^n) * t                      black-level correction, b = black_level
//     s     = t'^(1 / n)                               each sheet's transmittance, in [b, 1]
//     v     = T^-1(s)                                  the printer value
// so the stack transmits exactly t' and its black is b^n.
//
// Example: PrinterProfile p = load_printer("epson_stylus_pro_4800");
//          ToneMap tone{p, 1.0, 1.0, 2};  double v = tone.printer_value(0.5);

#include <filesystem>
#include <string>
#include <vector>

#include "core/units.hpp"

namespace rfd::print {

/// Paper and printable area, millimetres.
struct Paper {
    std::string name = "A4";  ///< for labels
    double width = 210.0;     ///< mm
    double height = 297.0;    ///< mm
    double margin = 3.0;      ///< mm the printer cannot reach on every side
};

struct PrinterProfile {
    std::string name;            ///< as printed on labels
    std::string file;            ///< profile file, for messages
    Dpi dpi_x{2880};             ///< dots per inch along the page's x (to the right)
    Dpi dpi_y{1440};             ///< dots per inch along the page's y (down)
    double gamma = 2.2;          ///< exponent of the code-to-transmittance law, > 0
    double max_density = 2.0;    ///< optical density of full ink, > 0 (T_ink = 10^-D)
    double black_level = 0.01;   ///< darkest transmittance aimed for per sheet, in [T_ink, 1)
    int sheets = 1;              ///< sheets stacked back to back by default (1 or 2)
    double film = 0.1;           ///< mm, thickness of one printed transparency (the holder's pockets)
    Paper paper;
    /// The measured curve, when the profile has one: ink values 0 = v_0 < ... < v_n = 1 and
    /// their transmittances 1 = T_0 > ... > T_n = T_ink. Empty: the power law.
    std::vector<double> tone_ink, tone_transmittance;

    /// Transmittance of full ink, 10^-max_density.
    double ink_transmittance() const;
    /// T(v) of the header: transmittance of printer value v in [0, 1].
    double transmittance(double v) const;
    /// The inverse: the printer value that transmits `t`, for t in [ink_transmittance(), 1]
    /// (clamped into that range).
    double printer_value(double t) const;
};

/// Reads a profile: `name_or_path` is a file path, or the name of a bundled profile in
/// printers/ ("epson_stylus_pro_4800"). Throws InputError naming file:line and key for a
/// missing, unknown or out-of-range key, IoError when the file cannot be read.
PrinterProfile load_printer(const std::string& name_or_path);

/// The profile file a printer name stands for: a file by that path, else a bundled profile
/// (a bare name: "epson_stylus_pro_4800"). IoError listing the bundled ones when neither.
std::filesystem::path printer_file(const std::string& name_or_path);
/// The same from TOML text; `name` stands for the file in messages.
PrinterProfile parse_printer(const std::string& toml_text, const std::string& name);
/// Folder of the bundled profiles (the source tree's printers/).
std::filesystem::path bundled_printer_folder();
/// The profile as TOML with every key written: parse_printer reads it back to an equal
/// profile, and two profiles print alike exactly when their texts are equal.
std::string printer_toml(const PrinterProfile& printer);
/// What prints a design when no profile is named: the bundled Epson's tone values and
/// paper at `dpi_x` x `dpi_y` (the design's [printer] resolution, or a pattern's).
PrinterProfile default_printer(Dpi dpi_x, Dpi dpi_y);

/// The tone mapping of the header, for one pattern.
struct ToneMap {
    PrinterProfile printer;
    double brightness = 1.0;  ///< > 0
    double white = 1.0;       ///< pattern value meant as full transmittance, > 0
    int sheets = 1;           ///< 1 or 2

    /// t' of the header: the stack's transmittance for pattern value p.
    double stack_transmittance(double pattern_value) const;
    /// s of the header: one sheet's transmittance.
    double sheet_transmittance(double pattern_value) const;
    /// v of the header: the printer value of one sheet.
    double printer_value(double pattern_value) const;
};

}  // namespace rfd::print
