#include "holders/openscad.hpp"

#include <chrono>

#include "core/command.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "holders/mesh_check.hpp"

namespace rfd::holders {

std::optional<std::filesystem::path> find_openscad() {
#ifdef RFD_OPENSCAD_PATH
    const std::string configured = RFD_OPENSCAD_PATH;
#else
    const std::string configured;
#endif
    return find_program(configured, {"/usr/bin/openscad", "/usr/local/bin/openscad"});
}

StlBuild build_stl(const std::filesystem::path& scad, const std::string& part, const std::filesystem::path& stl,
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
    const auto start = std::chrono::steady_clock::now();
    const CommandResult run = run_command("timeout --kill-after=5 " + std::to_string(limit) + " " +
                                          shell_quoted(openscad->string()) + " --hardwarnings -D " +
                                          shell_quoted("part=\"" + part + "\"") + " -o " +
                                          shell_quoted(temporary.string()) + " " + shell_quoted(scad.string()));
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const int code = run.exit_code;
    const std::string& output = run.output;
    if (code == 124 || code == 137)
        throw ToolError(SourceLocation{stl.string()}, "openscad took longer than " + std::to_string(limit) +
                                                          " s building part \"" + part + "\" of " + scad.string() +
                                                          " and was stopped");
    if (code != 0 || output.find("WARNING") != std::string::npos || output.find("ERROR") != std::string::npos ||
        !fs::exists(temporary) || fs::file_size(temporary) == 0)
        throw ToolError(SourceLocation{stl.string()}, "openscad failed on part \"" + part + "\" of " + scad.string() +
                                                          " (exit " + std::to_string(code) + "):\n" + output);
    const std::size_t slivers = remove_slivers(temporary);
    move_into_place(temporary, stl);
    guard.release();
    return {seconds, slivers};
}

}  // namespace rfd::holders
