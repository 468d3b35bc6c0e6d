// rfd: design, predict, print and build passive reflectance-field displays.

#include <cstdio>
#include <exception>

#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/progress.hpp"

int main(int argc, char** argv) {
    CLI::App app{"rfd: design, predict, print and build passive reflectance-field displays"};
    app.set_version_flag("--version", std::string("rfd ") + RFD_VERSION);
    app.require_subcommand(1);
    rfd::cli::GlobalOptions global;
    app.add_flag("--quiet,-q", global.quiet, "No progress output on stderr");
    app.parse_complete_callback([&] { rfd::Progress::set_quiet(global.quiet); });
    rfd::cli::add_optics_commands(app, global);
    rfd::cli::add_design_commands(app, global);
    CLI::App* capture = app.add_subcommand("capture", "Capture reflectance fields: virtual light stage, HDR assembly, light calibration, sampling patterns")->require_subcommand(1);
    rfd::cli::add_capture_commands(*capture, global);
    rfd::cli::add_adaptive_command(*capture, global);
    rfd::cli::add_study_command(*capture, global);
    rfd::cli::add_capture_implicit_command(*capture);
    rfd::cli::add_relight_commands(app, global);
    rfd::cli::add_capture_tool_commands(*capture, global);
    rfd::cli::add_pattern_commands(app, global);
    rfd::cli::add_print_commands(app, global);
    rfd::cli::add_simulate_commands(app, global);
    rfd::cli::add_holder_commands(app, global);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& error) {
        return app.exit(error);
    } catch (const rfd::Error& error) {
        std::fprintf(stderr, "rfd: error: %s\n", error.what());
        return error.exit_code();
    } catch (const std::exception& error) {
        std::fprintf(stderr, "rfd: error: %s\n", error.what());
        return 1;
    }
    return 0;
}
