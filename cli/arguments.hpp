#pragma once
// Command-line values several commands share, parsed with messages that name the option.

#include <array>
#include <cstddef>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "core/json.hpp"
#include "core/options.hpp"
#include "optics/design.hpp"
#include "optics/display.hpp"
#include "optics/meso_pixel.hpp"
#include "optics/model.hpp"
#include "predict/display_lights.hpp"
#include "patterns/angular_fields.hpp"
#include "patterns/encode.hpp"
#include "print/printed.hpp"
#include "relight/field.hpp"
#include "print/moire.hpp"
#include "print/printer.hpp"
#include "relight/interpolation.hpp"
#include "relight/render.hpp"
#include "relight/scene.hpp"

namespace rfd::cli {

/// MIN <= value <= MAX, with a message that names both ends as a user would write them
/// (CLI::Range prints 0.000001 to 1000000.000000).
CLI::Validator number_range(double min, double max);

/// An option declared once (core/options.hpp) added to `command` into `target`: `target`
/// set to its default (shown in --help), its range checked, its older spelling accepted.
CLI::Option* add_option(CLI::App& command, const NumberOption& option, double& target);
template <class Int>
CLI::Option* add_option(CLI::App& command, const IntegerOption& option, Int& target) {
    target = static_cast<Int>(option.fallback);
    std::string names(option.flag);
    if (!option.alias.empty()) names += "," + std::string(option.alias);
    return command.add_option(names, target, help_text(option))
        ->check(number_range(static_cast<double>(option.min), static_cast<double>(option.max)))
        ->default_str(std::to_string(option.fallback));
}

/// Checks of a number option whose messages a user can read (CLI::PositiveNumber's names
/// its range as 0 to 1.8e308 written out in full).
CLI::Validator positive_number();
CLI::Validator non_negative_number();
/// Text that reads as a number must be a finite one (nan and inf are refused; every
/// comparison with NaN is false, so CLI11's range checks let it through).
CLI::Validator finite_number_check();

/// "WIDTHxHEIGHT" (each within [1, 16384]); InputError naming --resolution otherwise.
std::pair<int, int> parse_resolution(const std::string& text);

/// --resolution and --samples-per-pixel on a loaded scene: an empty resolution or a
/// non-positive sample count leaves the scene's own value.
void apply_scene_overrides(relight::Scene& scene, const std::string& resolution, int samples_per_pixel);

inline constexpr const char* kLightSyntax = "THETA,PHI[,RADIUS][,R:G:B] (degrees; colour as irradiance per channel)";
/// --light THETA,PHI[,RADIUS][,R:G:B]: a distant light toward (THETA, PHI) in the field's
/// frame, a disc of RADIUS degrees if given; InputError quoting the option otherwise.
/// Three numbers within [-1, 1] of length 0.9 to 1.1 (a light file's X,Y,Z pasted) are
/// refused as ambiguous, unless the radius is written with its unit ("0.9deg").
relight::Light parse_light(const std::string& text);

inline constexpr const char* kLightDirectionSyntax = "X,Y,Z[,RADIUS][,R:G:B] (a direction as a light file writes it)";
/// --light-dir X,Y,Z[,RADIUS][,R:G:B]: the light toward direction (X, Y, Z) of the field's
/// frame (x right, y up, z toward the camera; normalised here), not below the horizon.
relight::Light parse_light_direction(const std::string& text);

/// --interpolation: "delaunay", "solid-angle" or "nearest"; InputError naming it otherwise.
relight::Interpolation parse_interpolation(const std::string& text);

/// An option that names one enumerator (core/names.hpp): only the names are accepted (a
/// usage error lists them), `target` keeps its value when the option is absent and shows
/// it as the default.
template <class Enum, std::size_t N>
CLI::Option* add_choice(CLI::App& command, const std::string& name, Enum& target, const std::array<Named<Enum>, N>& names,
                        const std::string& help) {
    CLI::Option* option = command.add_option_function<std::string>(
        name, [&target, &names](const std::string& text) { target = value_of(names, text, SourceLocation{"", 0, 0, ""}); },
        help);
    option->check(CLI::IsMember(names_of(names)));
    option->default_str(std::string(name_of(names, target)));
    return option;
}

/// --model: paraxial, exact or auto (the cheapest within --tolerance dots; optics/model.hpp).
CLI::Option* add_model_option(CLI::App& command, optics::ModelChoice& target);

/// The --printer profile (a file or a bundled name); without one, the thesis's printer's
/// tone values at the design's own [printer] resolution.
print::PrinterProfile printer_for(const optics::Design& design, const std::string& option);

/// The moire sheet's bands from --pitch and --pitch-y (empty: the defaults), as `rfd print
/// moire` lays them out.
print::MoireOptions moire_options(const optics::Design& design, const std::string& pitch, const std::string& pitch_y);


/// How a pattern is printed, for `rfd simulate` and its subcommands: --printer,
/// --brightness, --sheets (added to `command` by add_print_options).
struct PrintOptions {
    std::string printer;
    double brightness = print::kBrightnessOption.fallback;
    int sheets = static_cast<int>(print::kSheetsOption.fallback);  ///< 0: the profile's
};
void add_print_options(CLI::App& command, PrintOptions& options);
/// The pattern file as printed with those options, checked against the design.
print::PrintedTransparency printed_pattern(const optics::Design& design, const std::string& pattern_file,
                                           const PrintOptions& options);

/// The angular mapping a pattern was encoded with, from its rfd: attributes (identity
/// where absent); InputError naming the file and attribute when one is not a number.
patterns::AngularMapping read_pattern_mapping(const std::string& pattern_file);

/// The lights of --light, named in `frame`, as the display meets them: a field-frame light
/// at (theta, phi) goes through `mapping`, so it shows what the field shows under a light
/// from there; a display-frame one is where the display meets it.
std::vector<optics::DisplayLight> to_display_lights(const std::vector<std::string>& texts,
                                                    const patterns::AngularMapping& mapping, predict::LightFrame frame);

/// --region X,Y,W,H and --scale S for a command that reads a field: filled into `window`
/// when the command's callback runs (the region is parsed there).
struct WindowOptions {
    std::string region;
    double scale = relight::kFieldScaleOption.fallback;
    relight::ImageWindow window() const;
};
void add_window_options(CLI::App& command, WindowOptions& options);

/// The 6D field of a Design III/IV pattern, as `pattern encode-angular` and `simulate compare`
/// take it: SOURCE (a view set, or one field folder) or --procedural letters|diamonds.
struct AngularSource {
    std::string path, procedural, text = "0123456789ABCDEFGHIJKLMNOPQRST";
    double coverage = 1.0;
    WindowOptions window;
};
/// --procedural, --text, --coverage and the window options (SOURCE is the command's own).
void add_angular_source_options(CLI::App& command, AngularSource& source);
/// The field SOURCE names (InputError for a bad one); letters and diamonds fitted to `meso`.
std::unique_ptr<patterns::AngularField> angular_field(const AngularSource& source, const optics::MesoPixelOptics& meso,
                                                      optics::Model model);

/// Half the design's field of view (exact, the smallest wrap-over angle), degrees: the
/// default --max-angle of simulate rti and preview. InputError naming `design_file` when the
/// design has no field-of-view edge.
double field_of_view_half_angle_deg(const optics::DesignOptics& optics, const std::string& design_file);

/// --frame display|field for --light (predict::kDefaultLightFrame), with its help.
void add_frame_option(CLI::App& command, predict::LightFrame& frame);

/// FOLDER/summary.json of the folder an `rfd simulate` subcommand wrote, given as `option`
/// (--compare, --tolerance: the subcommand's name after the dashes); IoError naming the file
/// and the option when it is not there.
std::filesystem::path summary_file(const std::string& folder, const char* option);

}  // namespace rfd::cli
