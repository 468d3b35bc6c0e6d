#pragma once
// Output files are written to a temporary file beside the target and renamed into place,
// so an interrupted or failed write never leaves a half-written output behind.

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>

namespace rfd {

/// Writes `path` through `write`, atomically. Throws IoError naming the path when the
/// directory is missing or unwritable, or when the stream fails; `path` is then untouched.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write);

/// Convenience for whole text contents.
void write_text_file(const std::filesystem::path& path, const std::string& text);

/// Creates `dir` (and parents) or throws IoError naming it.
void ensure_directory(const std::filesystem::path& dir);

}  // namespace rfd
