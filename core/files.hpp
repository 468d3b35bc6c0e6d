#pragma once
// Output files are written to a temporary file beside the target and renamed into place,
// so an interrupted or failed write never leaves a half-written output behind.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <ostream>
#include <string>

#include "core/error.hpp"

namespace rfd {

/// Line `line` (1-based) of `path`: where a reader of line-oriented files found an error.
SourceLocation line_in(const std::filesystem::path& path, int line);

/// Writes `path` through `write`, atomically. Throws IoError naming the path when the
/// directory is missing or unwritable, or when the stream fails; `path` is then untouched.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write);

/// A fresh temporary path beside `target` that keeps its extension (tools that pick a
/// format from the extension, such as OpenImageIO, write it correctly). Throws IoError when
/// target's directory does not exist. The path is remembered until move_into_place() or
/// remove_temporary(), so that a signal ending the program removes the file
/// (remove_temporaries_on_signals).
std::filesystem::path temporary_sibling(const std::filesystem::path& target);

/// Renames a finished temporary file onto `target` once fsync says all of it is on the disk;
/// removes it and throws IoError on failure.
void move_into_place(const std::filesystem::path& temporary, const std::filesystem::path& target);

/// Removes an unfinished temporary file (if it exists) and forgets it.
void remove_temporary(const std::filesystem::path& temporary);

/// From now on SIGINT, SIGTERM, SIGHUP and SIGXFSZ remove every temporary file being
/// written and end the program with exit code 128 + the signal's number. A signal that was
/// ignored when the program started (nohup, a shell's background job) stays ignored.
void remove_temporaries_on_signals();

/// Convenience for whole text contents.
void write_text_file(const std::filesystem::path& path, const std::string& text);

/// The whole of a small text file (rfd's input files: at most 16 MB). IoError when it is
/// missing or unreadable, InputError when larger.
std::string read_text_file(const std::filesystem::path& path);

/// Creates `dir` (and parents) or throws IoError naming it.
void ensure_directory(const std::filesystem::path& dir);

/// A temporary file that is removed when the guard goes out of scope, unless released:
/// for writers that stream into temporary_sibling() and must leave nothing half-written
/// when an exception interrupts them.
class TemporaryFile {
public:
    explicit TemporaryFile(std::filesystem::path path) : path_(std::move(path)) {}
    ~TemporaryFile();
    TemporaryFile(const TemporaryFile&) = delete;
    TemporaryFile& operator=(const TemporaryFile&) = delete;
    const std::filesystem::path& path() const { return path_; }
    /// The file is finished (and moved into place): keep it.
    void release() { path_.clear(); }

private:
    std::filesystem::path path_;
};

/// An exclusive advisory lock (flock) on `file`, created if needed and left in place, held
/// for this object's life; a process that ends, however it ends, lets it go.
class ExclusiveLock {
public:
    /// Takes the lock, or throws IoError with `busy_message` when another process holds it
    /// (and IoError naming the file when it cannot be created).
    ExclusiveLock(const std::filesystem::path& file, const std::string& busy_message);
    ~ExclusiveLock();
    ExclusiveLock(const ExclusiveLock&) = delete;
    ExclusiveLock& operator=(const ExclusiveLock&) = delete;

private:
    int descriptor_ = -1;
};

/// True for a line of a text data file that holds nothing: blank, or a '#' comment.
bool is_blank_or_comment(const std::string& line);

/// Lets the process hold `files` open files at once, as far as its hard limit allows (a
/// field read in bands keeps every image open); the soft limit is often 1024.
void raise_open_file_limit(std::size_t files);

}  // namespace rfd
