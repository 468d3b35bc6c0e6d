#pragma once
// Running rfd's own steps as child processes, without a shell: each child in a process
// group of its own, so that a signal that stops the parent stops the child and everything
// it started (OpenSCAD, gnuplot), and the parent can wait for them and clean up.
//
// Example (rfd make):
//   forward_signals_to_children();
//   const pid_t pid = spawn_process("/usr/bin/rfd", {"--quiet", "print", "moire", ...},
//                                   {.working_folder = out, .output_file = out / "logs/moire.txt"});
//   const ChildExit done = wait_for_child();   // any child; retried across signals
//   if (received_signal() != 0) { ... remove what the stopped children half-wrote ... }

#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace rfd {

struct SpawnOptions {
    std::filesystem::path working_folder;  ///< where the child runs; empty: the parent's
    std::filesystem::path output_file;     ///< stdout and stderr are appended here (a relative path
                                           ///< from the parent's folder); empty: the parent's
};

/// Starts `program` with `arguments` (argv[1...]; no shell, no quoting), in a new process
/// group whose id is the child's pid, with default signal handling and an empty signal
/// mask. IoError naming the program when it cannot be started.
pid_t spawn_process(const std::filesystem::path& program, const std::vector<std::string>& arguments,
                    const SpawnOptions& options = {});

struct ChildExit {
    pid_t pid = -1;
    int exit_code = -1;  ///< the exit status, or 128 + the signal that ended it
};

/// Waits for any child started by spawn_process to end, and forgets it.
ChildExit wait_for_child();

/// From now on SIGINT, SIGTERM and SIGHUP do not end this program: they are passed on, as
/// SIGTERM, to the process groups of every child spawn_process started that has not been
/// waited for, and remembered (received_signal). The program then waits for its children,
/// cleans up, and ends itself (exit code 128 + the signal, by convention).
void forward_signals_to_children();

/// The first signal forward_signals_to_children() caught, or 0.
int received_signal();

}  // namespace rfd
