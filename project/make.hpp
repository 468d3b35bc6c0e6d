#pragma once
// `rfd make`: a project file turned into everything a maker prints, builds and checks.
//
// The chain is a list of steps, each one `rfd` command line with the files it reads and
// the files it writes (plan). make() runs them in order through a StepRunner, skipping
// the steps the manifest says are up to date (manifest.hpp), keeps each step's report in
// DIR/logs/STEP.txt, and finally writes DIR/README.txt and DIR/index.html. Because every
// step is an ordinary command, README.txt lists them: a user can re-run or vary any one.
//
// Example:
//   const Project project = load_project("examples/bottle_design1.toml");
//   make(project, "out/make1", run_rfd_in_a_subprocess, {});

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "project/project.hpp"

namespace rfd::project {

struct Step {
    std::string name;                              ///< short and unique: "pattern", "sheet_front_pdf"
    std::string title;                             ///< what it makes, for people
    std::vector<std::string> arguments;            ///< after "rfd"
    std::vector<std::filesystem::path> inputs;     ///< files and folders whose content it reads
    std::vector<std::filesystem::path> outputs;    ///< relative to the output folder
};

/// The steps that make `project` into `out`, in an order where every step's inputs are
/// made before it.
std::vector<Step> plan(const Project& project, const std::filesystem::path& out);

/// What running one step's command line gave: its exit code and what it printed.
struct StepResult {
    int exit_code = 0;
    std::string output;
};
using StepRunner = std::function<StepResult(const std::vector<std::string>& arguments)>;

struct MakeOptions {
    std::string rfd_identity;  ///< the running rfd (version and a hash of the program): part of every key
    bool force = false;        ///< run every step, whatever the manifest says
};

struct StepOutcome {
    std::string name, title;
    bool ran = false;          ///< false: skipped, up to date
    double seconds = 0.0;
};

/// Whom make() tells about each step, before (with the step's 0-based index and the count)
/// and after.
struct MakeListener {
    std::function<void(const Step&, int index, int count)> starting;
    std::function<void(const StepOutcome&)> finished;
};

/// Runs the plan into `out` (created if needed). A failing step throws ToolError naming
/// the step, its exit code, the last lines it printed and its log; the steps before it
/// stay made and recorded.
std::vector<StepOutcome> make(const Project& project, const std::filesystem::path& out, const StepRunner& run,
                              const MakeOptions& options, const MakeListener& listener = {});

/// The command line of `step` as a user would type it, shell-quoted where needed.
std::string command_line(const Step& step);

}  // namespace rfd::project
