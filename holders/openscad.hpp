#pragma once
// Running the openscad program (Debian's 2021.01) to turn a generated .scad into an STL.
// OpenSCAD is a program we run, not a library: CMake finds it (RFD_OPENSCAD_PATH), else the
// PATH. Warnings are errors (--hardwarnings): a warning in generated code is a bug.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>

namespace rfd::holders {

std::optional<std::filesystem::path> find_openscad();

struct StlBuild {
    double seconds = 0.0;         ///< wall-clock time of the openscad run
    std::size_t slivers = 0;      ///< sliver triangles of its tessellation removed (remove_slivers)
};

/// Builds `part` of `scad` (openscad -D part="...") into `stl` (binary, slivers removed),
/// through a temporary file moved into place only on success. Throws ToolError when
/// openscad is missing, fails, warns, or runs longer than `time_limit_s` (the message
/// carries its output); `stl` is then untouched.
StlBuild build_stl(const std::filesystem::path& scad, const std::string& part, const std::filesystem::path& stl,
                   double time_limit_s = 300.0);

}  // namespace rfd::holders
