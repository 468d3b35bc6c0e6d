#include "core/process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>

#include "core/error.hpp"

extern char** environ;

namespace rfd {
namespace {

// The children not yet waited for, for the signal handler to pass a signal on to. A
// handler may only touch lock-free memory and call async-signal-safe functions (kill).
std::array<std::atomic<pid_t>, 256> children{};
std::atomic<int> caught_signal{0};
static_assert(std::atomic<pid_t>::is_always_lock_free);

void remember_child(pid_t pid) {
    for (auto& slot : children) {
        pid_t expected = 0;
        if (slot.compare_exchange_strong(expected, pid)) return;
    }
    // Every slot taken: this child is not stopped by a signal to the parent. rfd make runs
    // a few steps at a time, never 256.
}

void forget_child(pid_t pid) {
    for (auto& slot : children) {
        pid_t expected = pid;
        if (slot.compare_exchange_strong(expected, 0)) return;
    }
}

extern "C" void pass_signal_on(int signal) {
    int none = 0;
    caught_signal.compare_exchange_strong(none, signal);
    for (auto& slot : children)
        if (const pid_t pid = slot.load(); pid > 0) kill(-pid, SIGTERM);
}

// posix_spawn's calls report an error number instead of setting errno.
void check(int error, const std::filesystem::path& program, const char* what) {
    if (error != 0)
        throw IoError("cannot start " + program.string() + " (" + what + "): " + std::strerror(error));
}

// Frees posix_spawn's attribute and file-action objects, however spawn_process leaves.
struct SpawnSetup {
    posix_spawnattr_t attributes;
    posix_spawn_file_actions_t actions;
    SpawnSetup() {
        posix_spawnattr_init(&attributes);
        posix_spawn_file_actions_init(&actions);
    }
    ~SpawnSetup() {
        posix_spawn_file_actions_destroy(&actions);
        posix_spawnattr_destroy(&attributes);
    }
    SpawnSetup(const SpawnSetup&) = delete;
    SpawnSetup& operator=(const SpawnSetup&) = delete;
};

}  // namespace

pid_t spawn_process(const std::filesystem::path& program, const std::vector<std::string>& arguments,
                    const SpawnOptions& options) {
    SpawnSetup setup;
    sigset_t defaults, empty;
    sigemptyset(&empty);
    sigemptyset(&defaults);
    for (const int signal : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) sigaddset(&defaults, signal);
    check(posix_spawnattr_setflags(&setup.attributes, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGDEF |
                                                          POSIX_SPAWN_SETSIGMASK),
          program, "attributes");
    check(posix_spawnattr_setpgroup(&setup.attributes, 0), program, "process group");
    check(posix_spawnattr_setsigdefault(&setup.attributes, &defaults), program, "signals");
    check(posix_spawnattr_setsigmask(&setup.attributes, &empty), program, "signal mask");
    if (!options.output_file.empty()) {
        check(posix_spawn_file_actions_addopen(&setup.actions, STDOUT_FILENO, options.output_file.c_str(),
                                               O_WRONLY | O_CREAT | O_APPEND, 0644),
              program, "output file");
        check(posix_spawn_file_actions_adddup2(&setup.actions, STDOUT_FILENO, STDERR_FILENO), program, "output");
    }
    // After the output file is open: a relative path names it from the parent's folder.
    if (!options.working_folder.empty())
        check(posix_spawn_file_actions_addchdir_np(&setup.actions, options.working_folder.c_str()), program,
              "working folder");
    std::vector<char*> argv;
    std::string name = program.string();
    argv.push_back(name.data());
    std::vector<std::string> copies = arguments;
    for (std::string& argument : copies) argv.push_back(argument.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    check(posix_spawn(&pid, name.c_str(), &setup.actions, &setup.attributes, argv.data(), environ), program,
          "spawn");
    remember_child(pid);
    // A signal that came between the spawn and remember_child found no child to pass on to.
    if (caught_signal.load() != 0) kill(-pid, SIGTERM);
    return pid;
}

ChildExit wait_for_child() {
    int status = 0;
    pid_t pid = 0;
    do pid = waitpid(-1, &status, 0);
    while (pid < 0 && errno == EINTR);
    if (pid < 0) throw IoError(std::string("waiting for a step: ") + std::strerror(errno));
    forget_child(pid);
    ChildExit exit{pid, -1};
    if (WIFEXITED(status)) exit.exit_code = WEXITSTATUS(status);
    else if (WIFSIGNALED(status)) exit.exit_code = 128 + WTERMSIG(status);
    return exit;
}

void forward_signals_to_children() {
    for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
        struct sigaction current {};
        if (sigaction(signal, nullptr, &current) == 0 && current.sa_handler == SIG_IGN) continue;
        struct sigaction action {};
        action.sa_handler = pass_signal_on;
        sigemptyset(&action.sa_mask);
        sigaction(signal, &action, nullptr);
    }
}

int received_signal() { return caught_signal.load(); }

}  // namespace rfd
