#pragma once
// Running the openscad program (Debian's 2021.01) to turn a generated .scad into an STL.
// OpenSCAD is a program we run, not a library: CMake finds it (RFD_OPENSCAD_PATH), else the
// PATH. Warnings are errors (--hardwarnings): a warning in generated code is a bug.

#include <filesystem>
#include <optional>
#include <string>

namespace rfd::holders {

std::optional<std::filesystem::path> find_openscad();

/// Builds `part` of `scad` (openscad -D part="...") into `stl`, through a temporary file
/// moved into place only on success. Throws ToolError when openscad is missing, fails,
/// warns, or runs longer than `time_limit_s` (the message carries its output); `stl` is
/// then untouched. Returns the wall-clock seconds the build took.
double build_stl(const std::filesystem::path& scad, const std::string& part, const std::filesystem::path& stl,
                 double time_limit_s = 300.0);

}  // namespace rfd::holders
