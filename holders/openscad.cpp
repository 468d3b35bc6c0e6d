#include "holders/openscad.hpp"

#include <chrono>
#include <cstdio>
#include <sys/wait.h>

#include "core/error.hpp"
#include "core/files.hpp"

namespace rfd::holders {
namespace {

std::string shell_quoted(const std::string& text) {
    std::string out = "'";
    for (const char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

}  // namespace

std::optional<std::filesystem::path> find_openscad() {
#ifdef RFD_OPENSCAD_PATH
    if (std::filesystem::exists(RFD_OPENSCAD_PATH)) return std::filesystem::path(RFD_OPENSCAD_PATH);
#endif
    for (const char* candidate : {"/usr/bin/openscad", "/usr/local/bin/openscad"})
        if (std::filesystem::exists(candidate)) return std::filesystem::path(candidate);
    return std::nullopt;
}

double build_stl(const std::filesystem::path& scad, const std::string& part, const std::filesystem::path& stl,
                 double time_limit_s) {
    namespace fs = std::filesystem;
    const auto openscad = find_openscad();
    if (!openscad)
        throw ToolError(SourceLocation{stl.string()},
                        "openscad is not installed (scripts/install-deps.sh installs it); the .scad is written, "
                        "the STL is not");
    const fs::path temporary = temporary_sibling(stl);
    TemporaryFile guard(temporary);
    const long limit = std::max(1L, static_cast<long>(time_limit_s + 0.5));
    const std::string command = "timeout --kill-after=5 " + std::to_string(limit) + " " +
                                shell_quoted(openscad->string()) + " --hardwarnings -D " +
                                shell_quoted("part=\"" + part + "\"") + " -o " + shell_quoted(temporary.string()) +
                                " " + shell_quoted(scad.string()) + " 2>&1";
    const auto start = std::chrono::steady_clock::now();
    FILE* pipe = popen(command.c_str(), "r");
    std::string output;
    if (pipe) {
        char buffer[512];
        while (fgets(buffer, sizeof buffer, pipe)) output += buffer;
    }
    const int status = pipe ? pclose(pipe) : -1;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const int code = status >= 0 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    if (code == 124 || code == 137)
        throw ToolError(SourceLocation{stl.string()}, "openscad took longer than " + std::to_string(limit) +
                                                          " s building part \"" + part + "\" of " + scad.string() +
                                                          " and was stopped");
    if (code != 0 || output.find("WARNING") != std::string::npos || output.find("ERROR") != std::string::npos ||
        !fs::exists(temporary) || fs::file_size(temporary) == 0)
        throw ToolError(SourceLocation{stl.string()}, "openscad failed on part \"" + part + "\" of " + scad.string() +
                                                          " (exit " + std::to_string(code) + "):\n" + output);
    move_into_place(temporary, stl);
    guard.release();
    return seconds;
}

}  // namespace rfd::holders
