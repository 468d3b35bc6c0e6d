// rfd calibrate: measurements of the printed test sheets that the rest of rfd then uses
// (calibrate/): the printer's tone curve from its step wedge.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "calibrate/camera.hpp"
#include "calibrate/tone.hpp"
#include "calibrate/tone_report.hpp"
#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image_io.hpp"
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
                          "printer's true tone curve, photographed from a pose with blur, vignetting and noise");
    struct Options {
        std::string sheet, printer, truth, out, light = "back";
        int steps = static_cast<int>(print::kWedgeStepsOption.fallback);
        int quality = static_cast<int>(calibrate::kJpegQualityOption.fallback);
        double tilt = 0, turn = 0, roll = 0, distance = calibrate::kCameraDistanceOption.fallback;
        double fill = calibrate::kFrameFillOption.fallback;
        calibrate::Camera camera;
        bool from_back = false;
        std::uint64_t seed = 1;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("SHEET", opt->sheet, "The sheet: wedge")->required()->check(CLI::IsMember({"wedge"}));
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
    cmd->add_flag("--from-back", opt->from_back, "Photographed through the film from its back (mirrored)");
    cmd->add_option("--seed", opt->seed, "Seed of the noise");
    cmd->add_option("--out", opt->out, "The photograph: .jpg (8-bit sRGB), .png or .exr (linear)")->required();
    cmd->callback([opt] {
        const print::PrinterProfile printer = print::load_printer(opt->printer);
        const print::PrinterProfile truth = opt->truth.empty() ? printer : print::load_printer(opt->truth);
        const print::WedgeSheet sheet = print::wedge_sheet(printer, opt->steps);
        calibrate::Camera camera = calibrate::framing_camera(printer.paper, opt->distance, opt->fill);
        camera.pose.tilt_deg = opt->tilt;
        camera.pose.turn_deg = opt->turn;
        camera.pose.roll_deg = opt->roll;
        camera.pose.from_back = opt->from_back;
        camera.blur = opt->camera.blur;
        camera.vignetting = opt->camera.vignetting;
        camera.photons = opt->camera.photons;
        camera.seed = opt->seed;
        const auto light = opt->light == "reflected" ? calibrate::ScanLight::Reflected : calibrate::ScanLight::Back;
        calibrate::write_photograph(opt->out, calibrate::simulated_wedge_photo(sheet, printer, truth, camera, light),
                                    opt->quality);
        std::printf("wrote %s\n", opt->out.c_str());
    });
}

}  // namespace

void add_calibrate_commands(CLI::App& app) {
    auto* calibrate = app.add_subcommand(
        "calibrate", "Measure the printed test sheets: the printer's tone curve; simulated photographs to try it");
    calibrate->require_subcommand(1);
    add_tone_command(*calibrate);
    add_simulate_photo_command(*calibrate);
}

}  // namespace rfd::cli
