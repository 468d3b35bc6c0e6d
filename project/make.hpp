#pragma once
// `rfd make`: a project file turned into everything a maker prints, builds and checks.
//
// The chain is a list of steps, each one `rfd` command line with the files it reads and
// the files it writes (plan). Every path in a step is relative to the output folder, where
// the step runs, or absolute when it lies outside it: README.txt's command lines run from
// its folder, and no output records where that folder is. make() runs the steps through a
// StepRunner, several at a time when they do not depend on one another, skipping the ones
// the manifest says are up to date (manifest.hpp); keeps each step's report in
// DIR/logs/STEP.txt; removes what an earlier plan made and this one does not; and finally
// writes DIR/README.txt and DIR/index.html. Because every step is an ordinary command,
// README.txt lists them: a user can re-run or vary any one.
//
// Example:
//   const Project project = load_project("examples/bottle_design1.toml");
//   ProcessStepRunner rfd("/usr/bin/rfd");
//   make(project, "out/make1", rfd, {.jobs = 2});

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "project/project.hpp"

namespace rfd::project {

struct Step {
    std::string name;                              ///< short and unique: "pattern", "sheet_front_pdf"
    std::string title;                             ///< what it makes, for people
    std::vector<std::string> arguments;            ///< after "rfd"; paths as in inputs and outputs
    std::vector<std::filesystem::path> inputs;     ///< files and folders whose content it reads:
                                                   ///< relative to the output folder, or absolute
    std::vector<std::filesystem::path> outputs;    ///< relative to the output folder
};

/// The steps that make `project`, in an order where every step's inputs are made before it.
std::vector<Step> plan(const Project& project);

/// For each step of `steps`, the earlier steps it reads an output of (an input that is an
/// output, lies inside an output folder, or holds an output).
std::vector<std::vector<std::size_t>> dependencies(const std::vector<Step>& steps);

/// Starts steps and says when they end. rfd make's runs each as an rfd process
/// (ProcessStepRunner); tests use a stand-in that writes what the step names.
class StepRunner {
public:
    virtual ~StepRunner() = default;
    /// Starts `step` with `out` as its working folder, what it prints appended to `log`;
    /// returns a handle that wait() gives back when it ends.
    virtual long start(const Step& step, const std::filesystem::path& out, const std::filesystem::path& log) = 0;
    struct Ended {
        long handle = 0;
        int exit_code = 0;
    };
    /// Blocks until one started step ends.
    virtual Ended wait() = 0;
    /// Non-zero when a signal asked to stop (and the running steps were told to): make()
    /// starts nothing more, waits for them, and removes what they half-wrote.
    virtual int stop_signal() const { return 0; }
};

/// Runs each step as `program --quiet ARGUMENTS...` (no shell) in a process group of its
/// own; a SIGINT, SIGTERM or SIGHUP to this process from its construction on is passed on
/// to the running steps' groups (core/process.hpp).
class ProcessStepRunner : public StepRunner {
public:
    explicit ProcessStepRunner(std::filesystem::path program);
    long start(const Step& step, const std::filesystem::path& out, const std::filesystem::path& log) override;
    Ended wait() override;
    int stop_signal() const override;

private:
    std::filesystem::path program_;
};

struct MakeOptions {
    std::string rfd_identity;        ///< the running rfd (version and a hash of the program): part of every key
    bool force = false;              ///< run every step, whatever the manifest says
    int jobs = 1;                    ///< steps run side by side at most; the outputs do not depend on it
    std::vector<std::string> only;   ///< make only these steps and those they read from (empty: all)
};

struct StepOutcome {
    std::string name, title;
    bool ran = false;          ///< false: skipped, up to date
    double seconds = 0.0;
};

/// Whom make() tells about each step as it ends (`done` steps of `count` are done) or is
/// found up to date.
struct MakeListener {
    std::function<void(const StepOutcome&, int done, int count)> finished;
};

/// Runs the plan into `out` (created if needed), holding a lock on it: another make() into
/// the same folder meanwhile is refused (IoError naming the folder). A failing step throws
/// ToolError naming the step, its exit code, the last lines it printed and its log, after
/// the steps running beside it have ended; every step that ended well stays made and
/// recorded. A signal (runner.stop_signal()) throws Interrupted once the running steps have
/// ended and what they wrote is removed. Outcomes are in the plan's order.
std::vector<StepOutcome> make(const Project& project, const std::filesystem::path& out, StepRunner& runner,
                              const MakeOptions& options, const MakeListener& listener = {});

/// The command line of `step` as a user would type it, shell-quoted where needed.
std::string command_line(const Step& step);

}  // namespace rfd::project
