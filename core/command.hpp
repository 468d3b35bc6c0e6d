#pragma once
// Running the external programs rfd uses (gnuplot, openscad, a user's capture command)
// through the shell: quoting, finding them, and capturing what they print.

#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string>

namespace rfd {

/// `text` single-quoted for the shell: the only character to escape is the quote itself.
std::string shell_quoted(const std::string& text);

/// The first of `configured` (a path CMake found, may be empty) and `candidates` that
/// exists, or nullopt.
std::optional<std::filesystem::path> find_program(const std::string& configured,
                                                  std::initializer_list<const char*> candidates);

struct CommandResult {
    int exit_code = -1;   ///< the program's exit status; -1 when it did not run to completion
    std::string output;   ///< stdout and stderr, interleaved
};

/// Runs `command` with /bin/sh, stderr joined to stdout, and waits for it.
CommandResult run_command(const std::string& command);

}  // namespace rfd
