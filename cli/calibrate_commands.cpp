// rfd calibrate: measurements of the printed test sheets that the rest of rfd then uses
// (calibrate/): the printer's tone curve from its step wedge.

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "calibrate/camera.hpp"
#include "calibrate/display_photo.hpp"
#include "calibrate/moire_photo.hpp"
#include "calibrate/pitch.hpp"
#include "calibrate/pitch_report.hpp"
#include "calibrate/registration.hpp"
#include "calibrate/tone.hpp"
#include "calibrate/tone_report.hpp"
#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image_io.hpp"
#include "core/units.hpp"
#include "optics/design_optics.hpp"
#include "optics/misalignment.hpp"
#include "predict/summaries.hpp"
#include "print/moire.hpp"
#include "print/printer.hpp"
#include "print/wedge.hpp"

namespace rfd::cli {
namespace {

void add_tone_command(CLI::App& calibrate) {
    auto* cmd = calibrate.add_subcommand(
        "tone", "The printer's tone curve and black level from scans or photographs of its printed step wedge "
                "(rfd print wedge), written as a printer profile that encoding, simulation and sheets then use");
    struct Options {
        std::string printer, out, report, light = "back";
        std::vector<std::string> scans;
        int steps = static_cast<int>(print::kWedgeStepsOption.fallback);
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("PRINTER", opt->printer, "The profile the wedge was printed with: a TOML file or a bundled name")
        ->required();
    cmd->add_option("SCAN", opt->scans, "Scans or photographs of the printed wedge (one page), averaged")->required();
    add_option(*cmd, print::kWedgeStepsOption, opt->steps);
    cmd->add_option("--light", opt->light,
                    "back: lit from behind (a light box, a scanner's transparency unit); reflected: the film on a "
                    "white backing, lit from the front, so the light crosses it twice")
        ->check(CLI::IsMember({"back", "reflected"}));
    cmd->add_option("--out", opt->out, "The calibrated printer profile to write (TOML)")->required();
    cmd->add_option("--report", opt->report, "Also a folder with the patches as CSV and the curves as a chart");
    cmd->callback([opt] {
        if (std::filesystem::path(opt->out).extension() != ".toml")
            throw InputError(SourceLocation{opt->out, 0, 0, "--out"}, "expected a .toml file");
        const print::PrinterProfile printer = print::load_printer(opt->printer);
        const print::WedgeSheet sheet = print::wedge_sheet(printer, opt->steps);
        if (sheet.pages > 1)
            throw InputError(SourceLocation{"--steps"}, "a wedge of " + std::to_string(opt->steps) + " steps takes " +
                                                            std::to_string(sheet.pages) + " pages of " +
                                                            printer.paper.name + "; calibrate from a one-page wedge");
        const auto light = opt->light == "reflected" ? calibrate::ScanLight::Reflected : calibrate::ScanLight::Back;
        std::vector<calibrate::WedgeReading> readings;
        for (const std::string& scan : opt->scans)
            readings.push_back(calibrate::measure_wedge(read_image(scan), scan, sheet, printer, light));
        const calibrate::ToneCalibration calibration = calibrate::calibrate_tone(printer, readings);
        std::fputs(calibrate::tone_text(calibration, readings, printer).c_str(), stdout);
        if (!opt->report.empty()) calibrate::write_tone_report(calibration, printer, opt->report);
        write_text_file(opt->out, "# Measured by rfd calibrate tone from " + std::to_string(readings.size()) +
                                      " scan(s) of a " + std::to_string(opt->steps) + "-step wedge.\n" +
                                      print::printer_toml(calibration.profile));
        std::printf("wrote %s\n", opt->out.c_str());
    });
}

void add_simulate_photo_command(CLI::App& calibrate) {
    auto* cmd = calibrate.add_subcommand(
        "simulate-photo", "A simulated photograph of a printed calibration sheet, to try the calibration without a "
                          "printer or to see what a good photograph looks like: the step wedge printed with a "
                          "printer's true tone curve, the moire sheet mounted in a display whose array has a "
                          "pitch error and a turn, or an assembled display whose pattern is shifted and turned, "
                          "photographed from a pose with blur, vignetting and noise");
    struct Options {
        std::string sheet, printer, truth, out, light = "back", design, pitch, pitch_y, array_on = "both", pattern;
        std::vector<double> shift{0.0, 0.0}, pattern_shift{0.0, 0.0};
        double pattern_rotation = 0, pattern_scale = 0;
        double pitch_error = 0, pitch_error_y = NAN, rotation = 0, light_tilt = 0, light_turn = 0;
        int pixels = 0;
        int steps = static_cast<int>(print::kWedgeStepsOption.fallback);
        int quality = static_cast<int>(calibrate::kJpegQualityOption.fallback);
        double tilt = 0, turn = 0, roll = 0, distance = calibrate::kCameraDistanceOption.fallback;
        double fill = calibrate::kFrameFillOption.fallback;
        calibrate::Camera camera;
        bool from_back = false;
        std::uint64_t seed = 1;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("SHEET", opt->sheet,
                    "The sheet: wedge (the step wedge on a light box), or moire (the pitch-calibration sheet mounted "
                    "in the display of --design in place of its pattern, lit from behind by the sun), or display (the "
                    "display of --design assembled with --pattern, lit from behind by the sun)")
        ->required()
        ->check(CLI::IsMember({"wedge", "moire", "display"}));
    cmd->add_option("PRINTER", opt->printer, "The profile the sheet is printed with: a TOML file or a bundled name")
        ->required();
    cmd->add_option("--true-printer", opt->truth,
                    "The profile whose tone curve the printer really has (default: PRINTER's own)");
    add_option(*cmd, print::kWedgeStepsOption, opt->steps);
    cmd->add_option("--light", opt->light, "back: lit from behind; reflected: on a white backing, lit from the front")
        ->check(CLI::IsMember({"back", "reflected"}));
    add_option(*cmd, calibrate::kCameraTiltOption, opt->tilt);
    add_option(*cmd, calibrate::kCameraTurnOption, opt->turn);
    add_option(*cmd, calibrate::kCameraRollOption, opt->roll);
    add_option(*cmd, calibrate::kCameraDistanceOption, opt->distance);
    add_option(*cmd, calibrate::kFrameFillOption, opt->fill);
    add_option(*cmd, calibrate::kBlurOption, opt->camera.blur);
    add_option(*cmd, calibrate::kVignettingOption, opt->camera.vignetting);
    add_option(*cmd, calibrate::kPhotonsOption, opt->camera.photons);
    add_option(*cmd, calibrate::kJpegQualityOption, opt->quality);
    cmd->add_flag("--from-back", opt->from_back, "Photographed through the film from its back (mirrored; wedge only)");
    cmd->add_option("--design", opt->design, "moire: the display whose array lies on the sheet");
    cmd->add_option("--pitch", opt->pitch, "moire: the sheet's x bands, as rfd print moire --pitch");
    cmd->add_option("--pitch-y", opt->pitch_y, "moire: the sheet's row bands, as rfd print moire --pitch-y");
    cmd->add_option("--pitch-error", opt->pitch_error,
                    "moire: the array's true pitch along a row over the design's, minus 1 (0.001: 0.1 % larger)")
        ->check(CLI::Range(-0.1, 0.1));
    cmd->add_option("--pitch-error-y", opt->pitch_error_y,
                    "moire: the same across the rows (default: --pitch-error)")
        ->check(CLI::Range(-0.1, 0.1));
    cmd->add_option("--array-rotation", opt->rotation,
                    "moire: the array's rows turned against the bands, degrees counter-clockwise")
        ->check(CLI::Range(-45.0, 45.0));
    cmd->add_option("--array-on", opt->array_on,
                    "moire: the measuring bands the array is centred on: both, or x or rows (an array shorter than "
                    "the two bands is photographed on each in turn)")
        ->check(CLI::IsMember({"both", "x", "rows"}));
    cmd->add_option("--array-shift", opt->shift, "moire: the array's centre from there, X,Y mm")
        ->delimiter(',')
        ->expected(2);
    cmd->add_option("--pattern", opt->pattern, "display: the pattern file printed and mounted");
    cmd->add_option("--pattern-shift", opt->pattern_shift,
                    "display: the pattern mounted this far right and up of where it belongs, X,Y mm")
        ->delimiter(',')
        ->expected(2)
        ->check(CLI::Range(-5.0, 5.0));
    cmd->add_option("--pattern-rotation", opt->pattern_rotation,
                    "display: the pattern turned counter-clockwise about the array's axis, degrees")
        ->check(CLI::Range(-10.0, 10.0));
    cmd->add_option("--pattern-scale", opt->pattern_scale,
                    "display: the pattern printed this much too large, relative (0.001: 0.1 %)")
        ->check(CLI::Range(-0.1, 0.1));
    cmd->add_option("--light-tilt", opt->light_tilt,
                    "moire, display: the sun's angle from the display's axis, degrees (the second photograph of a "
                    "turned pair: --light-turn plus 180 and --camera-roll 180)")
        ->check(CLI::Range(0.0, 80.0));
    cmd->add_option("--light-turn", opt->light_turn, "moire: the azimuth of that tilt, degrees");
    cmd->add_option("--camera-pixels", opt->pixels,
                    "Pixels along the picture's longer side (default: 1600 for the wedge, 4000 for the moire)")
        ->check(CLI::Range(200, 20000));
    cmd->add_option("--seed", opt->seed, "Seed of the noise");
    cmd->add_option("--out", opt->out, "The photograph: .jpg (8-bit sRGB), .png or .exr (linear)")->required();
    cmd->callback([opt] {
        const print::PrinterProfile printer = print::load_printer(opt->printer);
        const print::PrinterProfile truth = opt->truth.empty() ? printer : print::load_printer(opt->truth);
        const bool moire = opt->sheet == "moire", display = opt->sheet == "display";
        const int pixels = opt->pixels > 0 ? opt->pixels : moire ? 4000 : display ? 3000 : 1600;
        std::optional<optics::Design> design;
        if (moire || display) {
            const std::string what = moire ? "the moire sheet" : "the display";
            if (opt->design.empty()) throw InputError(SourceLocation{"--design"}, what + " needs a design");
            if (opt->from_back) throw InputError(SourceLocation{"--from-back"}, what + " is photographed from the front");
            design = optics::load_design(opt->design);
        }
        calibrate::Camera camera = calibrate::framing_camera(display ? calibrate::display_paper(*design) : printer.paper,
                                                             opt->distance, opt->fill, pixels);
        camera.pose.tilt_deg = opt->tilt;
        camera.pose.turn_deg = opt->turn;
        camera.pose.roll_deg = opt->roll;
        camera.pose.from_back = opt->from_back;
        camera.blur = opt->camera.blur;
        camera.vignetting = opt->camera.vignetting;
        camera.photons = opt->camera.photons;
        camera.seed = opt->seed;
        const Eigen::Vector3d light =
            optics::incident_direction(degrees_to_radians(opt->light_tilt), degrees_to_radians(opt->light_turn));
        if (display) {
            if (opt->pattern.empty()) throw InputError(SourceLocation{"--pattern"}, "the display needs its pattern");
            PrintOptions print_options;
            print_options.printer = opt->printer;
            const print::PrintedTransparency printed = printed_pattern(*design, opt->pattern, print_options);
            // As the sheet is printed: the corner lenslets' cells clear, with their markers.
            const print::MarkedTransparency sheet(printed, *design, printed.tone());
            const optics::MisalignedTransparency mounted(
                sheet, {{opt->pattern_shift[0], opt->pattern_shift[1]}, degrees_to_radians(opt->pattern_rotation),
                          opt->pattern_scale});
            calibrate::DisplayScene scene;
            scene.light = light;
            calibrate::write_photograph(opt->out, calibrate::simulated_display_photo(*design, mounted, scene, camera),
                                        opt->quality);
        } else if (moire) {
            const print::MoireSheet sheet =
                print::moire_sheet(*design, printer, moire_options(*design, opt->pitch, opt->pitch_y));
            calibrate::MoireScene scene;
            const auto on = opt->array_on == "x"      ? calibrate::MeasuringBands::X
                            : opt->array_on == "rows" ? calibrate::MeasuringBands::Rows
                                                      : calibrate::MeasuringBands::Both;
            scene.mounting.centre =
                calibrate::measuring_centre(sheet, on) + Eigen::Vector2d(opt->shift[0], opt->shift[1]);
            scene.mounting.rotation_deg = opt->rotation;
            scene.mounting.pitch_error_x = opt->pitch_error;
            scene.mounting.pitch_error_y = std::isnan(opt->pitch_error_y) ? opt->pitch_error : opt->pitch_error_y;
            scene.light = light;
            calibrate::write_photograph(opt->out, calibrate::simulated_moire_photo(*design, sheet, truth, scene, camera),
                                        opt->quality);
        } else {
            const print::WedgeSheet sheet = print::wedge_sheet(printer, opt->steps);
            const auto scan_light =
                opt->light == "reflected" ? calibrate::ScanLight::Reflected : calibrate::ScanLight::Back;
            calibrate::write_photograph(opt->out,
                                        calibrate::simulated_wedge_photo(sheet, printer, truth, camera, scan_light),
                                        opt->quality);
        }
        std::printf("wrote %s\n", opt->out.c_str());
    });
}

void add_pitch_command(CLI::App& calibrate) {
    auto* cmd = calibrate.add_subcommand(
        "pitch", "The lens array's true pitch (along a row and across the rows) and its rotation from photographs "
                 "of the moire sheet (rfd print moire) mounted in the display in its pattern's place, lit from "
                 "behind; writes the design with the measured pitch");
    struct Options {
        std::string design, printer, pitch, pitch_y, out, report;
        std::vector<std::string> photos;
        std::vector<double> sheet_scale{1.0, 1.0};
        int page = 1;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->design, "The design the sheet was printed for")->required();
    cmd->add_option("PHOTO", opt->photos, "Photographs of the mounted sheet, lit from behind")->required();
    cmd->add_option("--printer", opt->printer, "The profile the sheet was printed with (its paper), as rfd print moire");
    cmd->add_option("--pitch", opt->pitch, "The sheet's x bands, as given to rfd print moire --pitch");
    cmd->add_option("--pitch-y", opt->pitch_y, "The sheet's row bands, as given to rfd print moire --pitch-y");
    cmd->add_option("--page", opt->page, "The sheet's page in the photographs (1-based)");
    cmd->add_option("--sheet-scale", opt->sheet_scale,
                    "The sheet's true size over its nominal size along x and y, X,Y (from a ruler: the distance "
                    "between the corner marks' centres over the nominal)")
        ->delimiter(',')
        ->expected(2)
        ->check(CLI::Range(0.9, 1.1));
    cmd->add_option("--out", opt->out, "The design with the measured pitch to write (TOML)");
    cmd->add_option("--report", opt->report,
                    "Also a folder with every lenslet's reading (CSV) and the fitted line profiles as charts");
    cmd->callback([opt] {
        if (!opt->out.empty() && std::filesystem::path(opt->out).extension() != ".toml")
            throw InputError(SourceLocation{opt->out, 0, 0, "--out"}, "expected a .toml file");
        const optics::Design design = optics::load_design(opt->design);
        calibrate::check_pitch_readable(design);
        const print::PrinterProfile printer = printer_for(design, opt->printer);
        const print::MoireSheet sheet =
            print::moire_sheet(design, printer, moire_options(design, opt->pitch, opt->pitch_y));
        if (opt->page < 1 || opt->page > sheet.pages)
            throw InputError(SourceLocation{"--page"}, "the sheet has " + std::to_string(sheet.pages) + " page(s)");
        std::vector<calibrate::PitchReading> readings;
        for (const std::string& photo : opt->photos)
            readings.push_back(calibrate::read_pitch_photo(read_image(photo), photo, design, sheet, opt->page - 1));
        const calibrate::PitchCalibration calibration =
            calibrate::calibrate_pitch(design, readings, {opt->sheet_scale[0], opt->sheet_scale[1]});
        std::fputs(calibrate::pitch_text(calibration, readings).c_str(), stdout);
        if (!opt->report.empty()) calibrate::write_pitch_report(readings, opt->report);
        if (!opt->out.empty()) {
            write_text_file(opt->out, calibrate::calibrated_design_text(design, calibration, readings));
            std::printf("wrote %s\n", opt->out.c_str());
        }
    });
}

void add_registration_command(CLI::App& calibrate) {
    auto* cmd = calibrate.add_subcommand(
        "registration", "The printed pattern's shift and turn against the lens array from photographs of the "
                        "assembled display lit from behind by one small light: whether they are inside the design's "
                        "tolerances and how to move the pattern");
    struct Options {
        std::string design, pattern, tolerance, out;
        std::vector<std::string> photos, turned;
        PrintOptions print;
        double light_tilt = NAN, light_turn = 0;
        bool any_way_up = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->design, "The display's design")->required();
    cmd->add_option("PATTERN", opt->pattern, "The pattern file that was printed and mounted")->required();
    cmd->add_option("PHOTO", opt->photos,
                    "Photographs of the display from the front, lit from behind by one small light, upright (its top "
                    "up within 45 deg)")
        ->required();
    cmd->add_option("--turned", opt->turned,
                    "Photographs of the display turned by half a turn in its plane, the light and camera unchanged: "
                    "with the upright ones they cancel the light's tilt");
    cmd->add_flag("--any-way-up", opt->any_way_up,
                  "The photographs may show the display any way up: try each quarter turn (the pattern must not look "
                  "the same turned)");
    add_print_options(*cmd, opt->print);
    cmd->add_option("--light-tilt", opt->light_tilt,
                    "The light's angle from the display's axis, degrees, when known (otherwise a turned pair "
                    "measures it, or it is taken as head-on)")
        ->check(CLI::Range(0.0, 60.0));
    cmd->add_option("--light-turn", opt->light_turn, "The azimuth of that tilt from the display's +x, degrees");
    cmd->add_option("--tolerance", opt->tolerance, "Folder that rfd simulate tolerance wrote: judge against it");
    cmd->add_option("--out", opt->out, "Also the result as JSON (what rfd make reads)");
    cmd->callback([opt] {
        if (!opt->out.empty() && std::filesystem::path(opt->out).extension() != ".json")
            throw InputError(SourceLocation{opt->out, 0, 0, "--out"}, "expected a .json file");
        const optics::Design design = optics::load_design(opt->design);
        calibrate::check_registration_readable(design);  // before the pattern is read
        calibrate::RegistrationTolerances tolerances;
        if (!opt->tolerance.empty()) {
            for (const predict::ToleranceCurveRecord& curve :
                 predict::read_summary<predict::ToleranceSummary>(summary_file(opt->tolerance, "--tolerance")).curves) {
                if (curve.kind == "shift") tolerances.shift_mm = curve.tolerance.value_or(curve.max);
                if (curve.kind == "rotation") tolerances.rotation_deg = curve.tolerance.value_or(curve.max);
            }
        }
        const print::PrintedTransparency printed = printed_pattern(design, opt->pattern, opt->print);
        const print::MarkedTransparency sheet(printed, design, printed.tone());  // as printed, with its markers
        const calibrate::PatternMap map(sheet, design);
        std::vector<calibrate::RegistrationReading> readings;
        for (const std::string& photo : opt->photos)
            readings.push_back(calibrate::read_registration_photo(read_image(photo), photo, design, map,
                                                                  opt->any_way_up ? std::nullopt : std::optional(0)));
        for (const std::string& photo : opt->turned)
            readings.push_back(calibrate::read_registration_photo(read_image(photo), photo, design, map,
                                                                  opt->any_way_up ? std::nullopt : std::optional(2)));
        std::optional<Eigen::Vector3d> light;
        if (std::isfinite(opt->light_tilt))
            light = optics::incident_direction(degrees_to_radians(opt->light_tilt), degrees_to_radians(opt->light_turn));
        const calibrate::Registration registration = calibrate::combine_registration(design, readings, light);
        std::fputs(calibrate::registration_text(registration, readings, tolerances).c_str(), stdout);
        if (!opt->out.empty()) {
            predict::RegistrationSummary summary;
            summary.design = design.name;
            summary.photographs = static_cast<int>(readings.size());
            summary.light = registration.light;
            summary.shift_mm = {registration.shift_mm.x(), registration.shift_mm.y()};
            summary.sigma_shift_mm = {registration.sigma_shift_mm.x(), registration.sigma_shift_mm.y()};
            summary.rotation_deg = registration.rotation_deg;
            summary.sigma_rotation_deg = registration.sigma_rotation_deg;
            summary.scale_error = registration.pitch_error;
            summary.sigma_scale_error = registration.sigma_pitch_error;
            summary.tolerance_shift_mm = tolerances.shift_mm;
            summary.tolerance_rotation_deg = tolerances.rotation_deg;
            summary.inside = calibrate::inside_tolerances(registration, tolerances);
            predict::write_summary(opt->out, summary);
        }
    });
}

}  // namespace

void add_calibrate_commands(CLI::App& app) {
    auto* calibrate = app.add_subcommand(
        "calibrate", "Measure the printed test sheets and the assembled display: the printer's tone curve, the lens array's "
        "pitch, the pattern's registration; simulated photographs to try them");
    calibrate->require_subcommand(1);
    add_tone_command(*calibrate);
    add_pitch_command(*calibrate);
    add_registration_command(*calibrate);
    add_simulate_photo_command(*calibrate);
}

}  // namespace rfd::cli
