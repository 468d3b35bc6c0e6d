#pragma once
// What `rfd make` writes for people: DIR/README.txt (what to send to which printer, in
// which order, how to assemble, and the command of every step) and DIR/index.html (the
// same as a page, with the pictures).

#include <filesystem>
#include <string>
#include <vector>

#include "project/make.hpp"
#include "project/project.hpp"

namespace rfd::project {

/// The advice step's lines (advice.json in `out`), empty when it was not made or is not
/// what the step writes.
std::vector<std::string> advice_lines(const std::filesystem::path& out);

/// Writes README.txt and index.html into `out` for the steps made there.
void write_index(const Project& project, const std::filesystem::path& out, const std::vector<Step>& steps);

}  // namespace rfd::project
