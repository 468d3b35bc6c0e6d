#include "cli/arguments.hpp"

#include "optics/analysis.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <vector>

#include "core/error.hpp"
#include "core/number.hpp"
#include "core/sphere.hpp"
#include "core/text.hpp"
#include "core/units.hpp"
#include "predict/display_lights.hpp"
#include "patterns/raster.hpp"

namespace rfd::cli {

namespace {

double parse_number(const std::string& text, const std::string& light, const char* what, const char* option,
                    const char* syntax) {
    const std::optional<double> value = finite_number(text);
    if (!value)
        throw InputError(std::string(option) + " '" + light + "': " + what + " '" + text +
                         "' is not a number; expected " + syntax);
    return *value;
}

// A light's text split at its commas, its colour (a last part R:G:B) taken off.
struct LightParts {
    std::vector<std::string> numbers;
    Eigen::Vector3d colour = Eigen::Vector3d::Ones();
};

LightParts split_light(const std::string& text, const char* option, const char* syntax) {
    LightParts parts;
    std::stringstream stream(text);
    for (std::string part; std::getline(stream, part, ',');) parts.numbers.push_back(part);
    if (!text.empty() && text.back() == ',') parts.numbers.emplace_back();
    if (parts.numbers.size() >= 3 && parts.numbers.back().find(':') != std::string::npos) {
        std::vector<std::string> channels;
        std::stringstream colour_stream(parts.numbers.back());
        for (std::string c; std::getline(colour_stream, c, ':');) channels.push_back(c);
        if (channels.size() != 3)
            throw InputError(std::string(option) + " '" + text + "': colour '" + parts.numbers.back() +
                             "' must be R:G:B");
        for (int c = 0; c < 3; ++c) {
            parts.colour[c] = parse_number(channels[static_cast<std::size_t>(c)], text, "colour channel", option, syntax);
            if (parts.colour[c] < 0.0)
                throw InputError(std::string(option) + " '" + text + "': colour channels must be >= 0");
        }
        parts.numbers.pop_back();
    }
    return parts;
}

// The light toward unit `direction`, a disc when `radius` (degrees, "deg" allowed after it)
// is given.
relight::Light light_toward(const Eigen::Vector3d& direction, const std::string* radius, const Eigen::Vector3d& colour,
                            const std::string& text, const char* option, const char* syntax) {
    if (radius == nullptr) return relight::DirectionalLight{direction, colour};
    std::string number = *radius;
    if (number.size() > 3 && number.ends_with("deg")) number.resize(number.size() - 3);
    const double degrees = parse_number(number, text, "RADIUS", option, syntax);
    if (!(degrees > 0.0 && degrees <= 90.0))
        throw InputError(std::string(option) + " '" + text + "': RADIUS must be within (0, 90] degrees, got " + *radius);
    return relight::DiskLight{direction, degrees_to_radians(degrees), colour};
}

}  // namespace

relight::Light parse_light(const std::string& text) {
    const LightParts parts = split_light(text, "--light", kLightSyntax);
    const std::vector<std::string>& numbers = parts.numbers;
    if (numbers.size() < 2 || numbers.size() > 3)
        throw InputError("--light '" + text + "': expected " + kLightSyntax);
    const double theta = parse_number(numbers[0], text, "THETA", "--light", kLightSyntax);
    const double phi = parse_number(numbers[1], text, "PHI", "--light", kLightSyntax);
    if (numbers.size() == 3 && !numbers[2].ends_with("deg")) {
        // An .lp line's x,y,z pasted reads as a tiny disc near the zenith: refuse the guess.
        const std::optional<double> third = finite_number(numbers[2]);
        const Eigen::Vector3d xyz(theta, phi, third.value_or(0.0));
        if (third && xyz.cwiseAbs().maxCoeff() <= 1.0 && std::abs(xyz.norm() - 1.0) < 0.1)
            throw InputError("--light '" + text + "' reads as THETA " + numbers[0] + ", PHI " + numbers[1] +
                             " degrees and a disc of " + numbers[2] +
                             " degrees, but looks like a unit direction X,Y,Z (a light file's numbers): give a "
                             "direction as --light-dir " + text + "; for that disc, write its radius as " +
                             numbers[2] + "deg");
    }
    if (theta < 0.0 || theta > 90.0)
        throw InputError("--light '" + text + "': THETA must be within [0, 90] degrees from the zenith "
                         "(the field covers the upper hemisphere), got " + numbers[0]);
    const Eigen::Vector3d direction = direction_from_angles(degrees_to_radians(theta), degrees_to_radians(phi));
    return light_toward(direction, numbers.size() == 3 ? &numbers[2] : nullptr, parts.colour, text, "--light",
                        kLightSyntax);
}

relight::Light parse_light_direction(const std::string& text) {
    const LightParts parts = split_light(text, "--light-dir", kLightDirectionSyntax);
    const std::vector<std::string>& numbers = parts.numbers;
    if (numbers.size() < 3 || numbers.size() > 4)
        throw InputError("--light-dir '" + text + "': expected " + kLightDirectionSyntax);
    constexpr std::array<const char*, 3> kAxes{"X", "Y", "Z"};
    Eigen::Vector3d direction;
    for (int i = 0; i < 3; ++i)
        direction[i] = parse_number(numbers[static_cast<std::size_t>(i)], text, kAxes[static_cast<std::size_t>(i)],
                                    "--light-dir", kLightDirectionSyntax);
    if (!(direction.norm() > 1e-12))
        throw InputError("--light-dir '" + text + "': the direction has zero length");
    direction.normalize();
    if (direction.z() < 0.0)
        throw InputError("--light-dir '" + text + "': the direction points below the horizon (Z < 0); the field "
                         "covers the upper hemisphere, Z toward the camera");
    return light_toward(direction, numbers.size() == 4 ? &numbers[3] : nullptr, parts.colour, text, "--light-dir",
                        kLightDirectionSyntax);
}

std::pair<int, int> parse_resolution(const std::string& text) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') ||
        w < 1 || h < 1 || w > 16384 || h > 16384)
        throw InputError("--resolution: expected WIDTHxHEIGHT such as 256x128, got '" + text + "'");
    return {w, h};
}

void apply_scene_overrides(relight::Scene& scene, const std::string& resolution, int samples_per_pixel) {
    if (!resolution.empty()) {
        const auto [w, h] = parse_resolution(resolution);
        for (auto& camera : scene.cameras) {
            camera.width = w;
            camera.height = h;
        }
    }
    if (samples_per_pixel > 0) scene.samples_per_pixel = samples_per_pixel;
}

relight::Interpolation parse_interpolation(const std::string& text) {
    return value_of(relight::kInterpolationNames, text, SourceLocation{"", 0, 0, "--interpolation"});
}

CLI::Option* add_model_option(CLI::App& command, optics::ModelChoice& target) {
    return add_choice(command, "--model", target, optics::kModelChoiceNames,
                      "Optics: paraxial, exact, or auto (paraxial where it places every dot within the tolerance "
                      "of the exact trace, a quarter dot unless --tolerance says; exact for Designs III and IV)");
}

print::PrinterProfile printer_for(const optics::Design& design, const std::string& option) {
    if (!option.empty()) return print::load_printer(option);
    return print::default_printer(design.printer.dpi_x, design.printer.dpi_y);
}

print::MoireOptions moire_options(const optics::Design& design, const std::string& pitch, const std::string& pitch_y) {
    print::MoireOptions options;
    options.x = pitch.empty() ? print::default_pitch_range(design) : print::parse_pitch_range(pitch, "--pitch");
    if (!pitch_y.empty()) options.y = print::parse_pitch_range(pitch_y, "--pitch-y");
    return options;
}

namespace {

CLI::Validator lower_bound(const char* name, bool allow_zero) {
    return CLI::Validator(
        [allow_zero](std::string& text) -> std::string {
            double value = 0.0;
            if (!CLI::detail::lexical_cast(text, value)) return "expected a number, got " + text;
            if (value > 0.0 || (allow_zero && value == 0.0)) return {};
            return std::string("expected a number ") + (allow_zero ? ">= 0" : "> 0") + ", got " + text;
        },
        name);
}

}  // namespace

CLI::Validator number_range(double min, double max) {
    const std::string range = format_number(min) + " to " + format_number(max);
    return CLI::Validator(
        [min, max, range](std::string& text) -> std::string {
            double value = 0.0;
            if (!CLI::detail::lexical_cast(text, value)) return "expected a number, got " + text;
            if (value >= min && value <= max) return {};
            return "expected a number from " + range + ", got " + text;
        },
        // As CLI::Range describes itself, so that --help and docs/options.md read the same.
        "in [" + format_number(min) + " - " + format_number(max) + "]");
}

CLI::Option* add_option(CLI::App& command, const NumberOption& option, double& target) {
    target = option.fallback;
    std::string names(option.flag);
    if (!option.alias.empty()) names += "," + std::string(option.alias);
    return command.add_option(names, target, help_text(option))
        ->check(number_range(option.min, option.max))
        ->default_str(format_number(option.fallback));
}

CLI::Validator positive_number() { return lower_bound("POSITIVE", false); }
CLI::Validator non_negative_number() { return lower_bound("NONNEGATIVE", true); }

CLI::Validator finite_number_check() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            char* end = nullptr;
            const double value = std::strtod(text.c_str(), &end);
            if (end != text.c_str() && *end == '\0' && !std::isfinite(value)) return "expected a finite number, got " + text;
            return {};
        },
        "");
}

void add_print_options(CLI::App& command, PrintOptions& options) {
    command.add_option("--printer", options.printer,
                       "Printer profile (tone mapping) (default: the one the pattern was encoded for, else the Epson's "
                       "at the pattern's dpi)");
    add_option(command, print::kBrightnessOption, options.brightness);
    add_option(command, print::kSheetsOption, options.sheets);
}

print::PrintedTransparency printed_pattern(const optics::Design& design, const std::string& pattern_file,
                                           const PrintOptions& options) {
    const print::PrinterProfile printer =
        print::printer_for_pattern(design, pattern_file, options.printer);
    return print::PrintedTransparency(design, printer, pattern_file, options.brightness, options.sheets);
}

patterns::AngularMapping read_pattern_mapping(const std::string& pattern_file) {
    return patterns::mapping_of(patterns::read_pattern_info(pattern_file), pattern_file);
}

std::vector<optics::DisplayLight> to_display_lights(const std::vector<std::string>& texts,
                                                 const patterns::AngularMapping& mapping, predict::LightFrame frame) {
    std::vector<optics::DisplayLight> lights;
    for (const std::string& text : texts)
        lights.push_back(predict::display_light(predict::light_in_field_frame(parse_light(text), frame, mapping), mapping));
    return lights;
}

relight::ImageWindow WindowOptions::window() const {
    relight::ImageWindow window = region.empty() ? relight::ImageWindow{} : relight::parse_region(region, "--region");
    window.scale = scale;
    return window;
}

void add_window_options(CLI::App& command, WindowOptions& options) {
    command.add_option("--region", options.region,
                       "Only this part of every image of the field, X,Y,W,H in pixels (leave out a capture's "
                       "calibration spheres and frame)");
    add_option(command, relight::kFieldScaleOption, options.scale);
}

double field_of_view_half_angle_deg(const optics::DesignOptics& optics, const std::string& design_file) {
    const optics::DesignSummary summary = optics::summarise(optics);
    if (!summary.field_of_view_deg)
        throw InputError(SourceLocation{design_file}, "the design has no field of view edge: give --max-angle");
    return 0.5 * *summary.field_of_view_deg;
}

void add_frame_option(CLI::App& command, predict::LightFrame& frame) {
    frame = predict::kDefaultLightFrame;
    add_choice(command, "--frame", frame, predict::kLightFrameNames,
               "The frame --light is named in: display (0,0 is a lamp straight behind the display, THETA the angle "
               "to its axis) or field (as the field was captured, before --tilt/--turn/--angle-scale)");
}

std::filesystem::path summary_file(const std::string& folder, const char* option) {
    const std::filesystem::path file = std::filesystem::path(folder) / "summary.json";
    if (!std::filesystem::exists(file))
        throw IoError(SourceLocation{file.string(), 0, 0, option},
                      std::string("cannot open (expected the folder that rfd simulate ") + (option + 2) + " --out wrote)");
    return file;
}

}  // namespace rfd::cli
