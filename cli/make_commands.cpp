// rfd make: a project file into the pattern, the print sheets, the holder and the
// predicted display, skipping what is up to date (project/make.hpp).

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "cli/commands.hpp"
#include "core/command.hpp"
#include "core/error.hpp"
#include "predict/summaries.hpp"
#include "project/index.hpp"
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
        int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
        std::vector<std::string> only;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("PROJECT", opt->project, "Project file (TOML; examples/ has two)")->required();
    cmd->add_option("--out", opt->out, "Output folder")->required();
    cmd->add_flag("--force", opt->force, "Make every step again, whatever the manifest says");
    cmd->add_flag("--dry-run", opt->dry_run, "Print the steps' commands (run from the output folder) and make nothing");
    cmd->add_option("--jobs,-j", opt->jobs, "Steps run side by side at most (default: the machine's cores; the outputs are the same for any)")
        ->capture_default_str()
        ->check(CLI::Range(1, 64));
    cmd->add_option("--only", opt->only, "Make only these steps (names as rfd make prints them) and the steps they read from")
        ->expected(1, -1);
    cmd->callback([opt] {
        const project::Project project = project::load_project(opt->project);
        if (opt->dry_run) {
            std::printf("cd %s\n", shell_quoted(opt->out).c_str());
            for (const project::Step& step : project::plan(project))
                std::printf("# %s: %s\n%s\n", step.name.c_str(), step.title.c_str(), command_line(step).c_str());
            return;
        }
        const fs::path program = this_program();
        project::MakeOptions options;
        options.rfd_identity = std::string("rfd ") + RFD_VERSION + " " + project::content_hash(program);
        options.force = opt->force;
        options.jobs = opt->jobs;
        options.only = opt->only;
        project::ProcessStepRunner runner(program);
        std::printf("%s -> %s\n", opt->project.c_str(), opt->out.c_str());
        std::fflush(stdout);
        project::MakeListener listener;
        const fs::path out = opt->out;
        listener.finished = [out](const project::StepOutcome& step, int done, int count) {
            const int digits = count >= 10 ? 2 : 1;
            std::printf("  [%*d/%d] %-16s ", digits, done, count, step.name.c_str());
            if (step.ran) std::printf("made in %.1f s\n", step.seconds);
            else std::printf("up to date\n");
            // The advice comes before the long steps: say it as soon as it is made.
            if (step.name == "advice")
                for (const std::string& line : project::advice_lines(out)) std::printf("           %s\n", line.c_str());
            std::fflush(stdout);
        };
        const std::vector<project::StepOutcome> outcomes = project::make(project, opt->out, runner, options, listener);
        if (opt->only.empty() && fs::exists(fs::path(opt->out) / "verdict.json")) {
            const auto verdict = predict::read_summary<predict::VerdictReport>(fs::path(opt->out) / "verdict.json");
            std::printf("verdict: %s\n  on this field: %s\n  on the design: %s\n", verdict.line.c_str(),
                        verdict.field_line.c_str(), verdict.design_line.c_str());
        }
        int ran = 0;
        for (const auto& step : outcomes) ran += step.ran ? 1 : 0;
        std::printf("%d step(s) made, %zu up to date. What to print and how to assemble: %s/README.txt (and "
                    "index.html)\n",
                    ran, outcomes.size() - static_cast<std::size_t>(ran), opt->out.c_str());
    });
}

}  // namespace rfd::cli
