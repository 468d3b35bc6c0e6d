// rfd: design, predict, print and build passive reflectance-field displays.

#include <malloc.h>

#include <cstdio>
#include <exception>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/progress.hpp"

namespace {

// What every command shares, added once all exist: --quiet anywhere on the command line,
// every number finite (CLI11's range checks let NaN through), no placeholder shown as a default.
void add_shared_rules(CLI::App& command, bool& quiet) {
    for (CLI::Option* option : command.get_options()) {
        if (option->get_type_name().starts_with("FLOAT")) option->check(rfd::cli::finite_number_check());
        // An empty list is no default; a default the help describes ("default: the design's")
        // is not the placeholder the option starts with.
        if (option->get_default_str() == "[]" || option->get_description().find("(default:") != std::string::npos)
            option->default_str("");
    }
    for (CLI::App* sub : command.get_subcommands({})) {
        sub->add_flag("--quiet,-q", quiet, "No progress output on stderr");
        add_shared_rules(*sub, quiet);
    }
}

}  // namespace

int main(int argc, char** argv) {
    // Bands of camera-size images (a field read a band of rows at a time) are allocated and
    // freed over and over: mapped and unmapped by glibc each time, every page would be
    // faulted in and zeroed again (40 % of relighting a 24 Mpx field). Kept on the heap up
    // to glibc's largest threshold, and not trimmed at once, they are reused.
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 256 << 20);
    rfd::remove_temporaries_on_signals();
    CLI::App app{"rfd: design, predict, print and build passive reflectance-field displays"};
    app.set_version_flag("--version", std::string("rfd ") + RFD_VERSION);
    app.require_subcommand(1);
    // Every option shows its default in --help and docs/options.md from the value it starts
    // with, so no help text repeats a default by hand.
    app.option_defaults()->always_capture_default();
    bool quiet = false;  // every command's --quiet (add_shared_rules) sets it too
    app.add_flag("--quiet,-q", quiet, "No progress output on stderr");
    app.parse_complete_callback([&] { rfd::Progress::set_quiet(quiet); });
    rfd::cli::add_optics_commands(app);
    rfd::cli::add_design_commands(app);
    CLI::App* capture = app.add_subcommand("capture", "Capture reflectance fields: virtual light stage, HDR assembly, light calibration, sampling patterns")->require_subcommand(1);
    rfd::cli::add_capture_commands(*capture);
    rfd::cli::add_adaptive_command(*capture);
    rfd::cli::add_study_command(*capture);
    rfd::cli::add_capture_implicit_command(*capture);
    rfd::cli::add_relight_commands(app);
    rfd::cli::add_capture_tool_commands(*capture);
    rfd::cli::add_pattern_commands(app);
    rfd::cli::add_print_commands(app);
    rfd::cli::add_calibrate_commands(app);
    rfd::cli::add_simulate_commands(app);
    rfd::cli::add_holder_commands(app);
    rfd::cli::add_make_command(app);
    rfd::cli::add_options_doc_command(app);
    add_shared_rules(app, quiet);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& error) {
        // A wrong command line is bad input like any other, whatever code CLI11 gives it;
        // --help and --version exit 0.
        const int code = app.exit(error);
        return code == 0 ? 0 : rfd::InputError(error.what()).exit_code();
    } catch (const rfd::Error& error) {
        std::fprintf(stderr, "rfd: error: %s\n", error.what());
        return error.exit_code();
    } catch (const std::exception& error) {
        std::fprintf(stderr, "rfd: error: %s\n", error.what());
        return 1;
    }
    return 0;
}
