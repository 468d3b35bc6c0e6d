#pragma once
// The project file: everything `rfd make` needs to go from a reflectance field to what a
// maker prints and builds, in one TOML file (docs/formats.md, "Project files").
//
//   [project]  name, design, printer, printer_3d   (bundled names or paths)
//   [source]   field (a folder or .lp), scene + lights + resolution, or procedural + text +
//              resolution; region, scale
//   [encode]   tilt_deg, turn_deg, angle_scale, model, interpolation, basis, fit, margin_mm
//   [make]     sheets, copies, moire, wedge, holder, compare_sweep, tolerance, preview_lights
//   [optimize] enabled, iterations, spacing_mm, core_weight: the pattern is optimised through
//              the simulator (rfd pattern optimize) and the sheets print that one, unless
//              enabled = false
//   [calibration] what the maker photographed, each optional:
//              wedge_photos, light: the printed step wedge; the printer's tone curve is
//              measured from them (rfd calibrate tone) and everything is printed and
//              predicted with the measured profile;
//              moire_photos, moire_page: the moire sheet under the lens array; the array's
//              pitch is measured (rfd calibrate pitch) and everything after is encoded,
//              printed and predicted for the measured design;
//              display_photos, turned_photos, display_light_tilt_deg, display_light_turn_deg:
//              the assembled display lit from behind; the pattern's registration is measured
//              (rfd calibrate registration) and judged against the assembly tolerances
//
// Paths are relative to the project file. Every key is checked like every other input
// file: an unknown key or a value out of range is an error naming file, line and key.

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "patterns/encode.hpp"
#include "patterns/raster.hpp"
#include "predict/compare.hpp"
#include "predict/optimize.hpp"
#include "predict/preview.hpp"

namespace rfd::project {

/// Where the reflectance field comes from: a field on disk, a scene rendered on the virtual
/// light stage, or a procedural test field (`rfd pattern field`).
struct Source {
    std::optional<std::filesystem::path> field;   ///< folder or .lp file
    std::optional<std::filesystem::path> scene;   ///< scene TOML
    std::optional<std::string> procedural;        ///< "letters", "bars" or "diamonds"
    std::string text = "SIG08";                   ///< procedural letters: one per light
    int lights = 400;                             ///< scene: light directions to render
    std::optional<std::array<int, 2>> resolution; ///< scene, procedural: image size (default: their own)
    std::optional<std::array<int, 4>> region;     ///< x, y, width, height of the object, pixels
    std::optional<double> scale;                  ///< applied after the region
};

/// The encoder's options, as `rfd pattern encode` names them.
struct Encoding {
    /// nullopt: "auto", the tilt with the most of the field's lights inside the range.
    std::optional<double> tilt_deg = patterns::kTiltOption.fallback;
    double turn_deg = patterns::kTurnOption.fallback;
    double angle_scale = patterns::kAngleScaleOption.fallback, margin_mm = patterns::kMarginOption.fallback;
    std::string model = "auto", interpolation = "delaunay", fit = "cover";
    /// How the field is predicted between its lights (rfd pattern encode --basis): unset, "auto"
    /// for a captured field ([source] field), interpolation for fields rfd makes itself.
    std::optional<std::string> basis;
};

/// What to make besides the pattern.
struct Outputs {
    std::vector<std::string> sheet_formats{"pdf", "tif"};  ///< of the front (and back) sheets
    int copies = 0;           ///< of the pattern per sheet; 0: as many as fit (spares to cut)
    bool moire = true;        ///< the pitch calibration sheet
    bool wedge = true;        ///< the step wedge that measures the printer's tone curve
    bool holder = true;       ///< the holder's .scad and STLs with their checks
    int compare_sweep = static_cast<int>(predict::kSweepOption.fallback);  ///< predicted against relit at this many lights (0: none)
    bool tolerance = true;    ///< assembly tolerances
    int preview_lights = static_cast<int>(predict::kPreviewLightsOption.fallback);  ///< directions precomputed for the preview page (0: no light control)
};

/// `rfd pattern optimize`'s settings, when the project asks for an optimised pattern.
struct Optimization {
    int iterations = static_cast<int>(predict::kIterationsOption.fallback);
    double spacing_mm = predict::kNodeSpacingOption.fallback;
    double core_weight = predict::kCoreWeightOption.fallback;
};

/// What the maker photographed: the printed test sheets, then the assembled display.
struct Calibration {
    std::vector<std::filesystem::path> wedge_photos;  ///< scans or photographs of print/wedge.pdf
    std::string light = "back";                       ///< how they were lit: "back" or "reflected"
    std::vector<std::filesystem::path> moire_photos;  ///< of print/moire.pdf under the lens array
    int moire_page = 1;                               ///< the sheet's page they show
    std::vector<std::filesystem::path> display_photos;  ///< of the assembled display, upright
    std::vector<std::filesystem::path> turned_photos;   ///< the same turned by half a turn
    std::optional<double> display_light_tilt_deg;       ///< the lamp's tilt from the axis, when known
    double display_light_turn_deg = 0.0;                ///< and its azimuth
};

struct Project {
    std::filesystem::path file;      ///< the project file itself
    std::string name;
    std::filesystem::path design;    ///< resolved design file
    std::string printer;             ///< film printer: a bundled name or a resolved path
    std::filesystem::path printer_3d;///< resolved 3D printer profile
    Source source;
    Encoding encoding;
    Outputs outputs;
    std::optional<Optimization> optimization;  ///< nullopt: [optimize] enabled = false, the direct encoding
    Calibration calibration;
    /// Why the design's pitch or registration cannot be measured from photographs (an array
    /// too small: calibrate::check_pitch_readable, check_registration_readable); empty when
    /// it can.
    std::string pitch_refusal, registration_refusal;
};

/// A project-file key declared as an option (core/options.hpp) in the library that owns
/// it: load_project reads it through that declaration, docs/options.md lists it from here,
/// and test_project refuses each out of its range.
struct DeclaredKey {
    std::string_view table;  ///< "source", "encode", "make", "optimize"
    std::variant<NumberOption, IntegerOption> option;
};
const std::vector<DeclaredKey>& declared_keys();

/// Reads and checks a project file. Bundled names: designs ("design1": designs/design1.toml),
/// film printers (printers/), 3D printers (holders/profiles/). InputError naming the file,
/// line and key for anything wrong, including a design `rfd make` cannot build (III, IV).
Project load_project(const std::filesystem::path& file);

/// The source tree's folders of bundled designs and 3D printer profiles.
std::filesystem::path bundled_design_folder();
std::filesystem::path bundled_holder_profile_folder();

}  // namespace rfd::project
