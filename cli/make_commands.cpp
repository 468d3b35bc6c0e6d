// rfd make: a project file into the pattern, the print sheets, the holder and the
// predicted display, skipping what is up to date (project/make.hpp).

#include <cstdio>
#include <fstream>
#include <filesystem>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/commands.hpp"
#include "core/command.hpp"
#include "core/error.hpp"
#include "project/make.hpp"
#include "project/manifest.hpp"
#include "project/project.hpp"

namespace rfd::cli {
namespace {

namespace fs = std::filesystem;

// This very program: every step runs it again with the step's arguments, in a process of
// its own, so a step behaves exactly as the command a user would type.
fs::path this_program() {
    std::error_code ec;
    const fs::path self = fs::read_symlink("/proc/self/exe", ec);
    if (ec) throw IoError("cannot find the running rfd program (/proc/self/exe): " + ec.message());
    return self;
}

}  // namespace

void add_make_command(CLI::App& app) {
    auto* cmd = app.add_subcommand(
        "make", "From a project file to everything a maker prints and builds: pattern, print sheets, calibration "
                "sheets, holder STLs, the predicted display, README.txt and index.html; re-running re-makes only "
                "what changed");
    struct Options {
        std::string project, out;
        bool force = false, dry_run = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("PROJECT", opt->project, "Project file (TOML; examples/ has two)")->required();
    cmd->add_option("--out", opt->out, "Output folder")->required();
    cmd->add_flag("--force", opt->force, "Make every step again, whatever the manifest says");
    cmd->add_flag("--dry-run", opt->dry_run, "Print the steps' commands and make nothing");
    cmd->callback([opt] {
        const project::Project project = project::load_project(opt->project);
        if (opt->dry_run) {
            for (const project::Step& step : project::plan(project, opt->out))
                std::printf("# %s: %s\n%s\n", step.name.c_str(), step.title.c_str(), command_line(step).c_str());
            return;
        }
        const fs::path program = this_program();
        project::MakeOptions options;
        options.rfd_identity = std::string("rfd ") + RFD_VERSION + " " + project::content_hash(program);
        options.force = opt->force;
        const project::StepRunner run = [&](const std::vector<std::string>& arguments) {
            std::string command = shell_quoted(program.string()) + " --quiet";
            for (const std::string& argument : arguments) command += " " + shell_quoted(argument);
            const CommandResult result = run_command(command);
            return project::StepResult{result.exit_code, result.output};
        };
        std::printf("%s -> %s\n", opt->project.c_str(), opt->out.c_str());
        std::fflush(stdout);
        project::MakeListener listener;
        listener.starting = [](const project::Step& step, int index, int count) {
            const int digits = count >= 10 ? 2 : 1;
            std::printf("  [%*d/%d] %-16s ", digits, index + 1, count, step.name.c_str());
            std::fflush(stdout);
        };
        listener.finished = [](const project::StepOutcome& step) {
            if (step.ran) std::printf("made in %.1f s\n", step.seconds);
            else std::printf("up to date\n");
            std::fflush(stdout);
        };
        std::vector<project::StepOutcome> outcomes;
        try {
            outcomes = project::make(project, opt->out, run, options, listener);
        } catch (const Error&) {
            std::printf("failed\n");
            throw;
        }
        std::ifstream verdict(fs::path(opt->out) / "verdict.json");
        if (verdict) {
            const nlohmann::json v = nlohmann::json::parse(verdict, nullptr, false);
            if (!v.is_discarded() && v.contains("line")) std::printf("verdict: %s\n", v["line"].get<std::string>().c_str());
        }
        int ran = 0;
        for (const auto& step : outcomes) ran += step.ran ? 1 : 0;
        std::printf("%d step(s) made, %zu up to date. What to print and how to assemble: %s/README.txt (and "
                    "index.html)\n",
                    ran, outcomes.size() - static_cast<std::size_t>(ran), opt->out.c_str());
    });
}

}  // namespace rfd::cli
