#include "core/command.hpp"

#include <cstdio>

#include <sys/wait.h>

namespace rfd {

std::string shell_quoted(const std::string& text) {
    std::string quoted = "'";
    for (const char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return quoted + "'";
}

std::optional<std::filesystem::path> find_program(const std::string& configured,
                                                  std::initializer_list<const char*> candidates) {
    if (!configured.empty() && std::filesystem::exists(configured)) return std::filesystem::path(configured);
    for (const char* candidate : candidates)
        if (std::filesystem::exists(candidate)) return std::filesystem::path(candidate);
    return std::nullopt;
}

CommandResult run_command(const std::string& command) {
    CommandResult result;
    FILE* pipe = popen((command + " 2>&1").c_str(), "r");
    if (!pipe) return result;
    char buffer[512];
    while (fgets(buffer, sizeof buffer, pipe)) result.output += buffer;
    const int status = pclose(pipe);
    if (status != -1 && WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
    return result;
}

}  // namespace rfd
