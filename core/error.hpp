#pragma once
// Errors in rfd travel on three channels that are never mixed:
//  1. programmer invariants: RFD_CHECK (always on) and RFD_DCHECK (debug only) abort;
//  2. expected physical outcomes (a ray that misses, total internal reflection) are values,
//     never exceptions: numerical code does not throw;
//  3. bad input, I/O and tool failures throw rfd::Error, caught once in the CLI's main().

#include <stdexcept>
#include <string>

namespace rfd {

/// Where in an input file a problem was found. Empty fields are simply not printed.
struct SourceLocation {
    std::string file;  ///< path as the user gave it
    int line = 0;      ///< 1-based line, 0 if unknown
    int column = 0;    ///< 1-based column, 0 if unknown
    std::string key;   ///< dotted key path inside the file, e.g. "planes.A.pitch_mm"

    /// "file:line:column: key" with whatever parts are known.
    std::string to_string() const;
};

/// Base of every error a user can cause. what() is the complete, printable message.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
    Error(const SourceLocation& where, const std::string& message);
    /// Process exit code the CLI uses for this kind of error.
    virtual int exit_code() const { return 1; }
};

/// A file's content is malformed or describes something impossible.
class InputError : public Error {
public:
    using Error::Error;
    int exit_code() const override { return 2; }
};

/// Reading or writing a file failed.
class IoError : public Error {
public:
    using Error::Error;
    int exit_code() const override { return 3; }
};

/// An external program (gnuplot, openscad) is missing or failed.
class ToolError : public Error {
public:
    using Error::Error;
    int exit_code() const override { return 4; }
};

/// The program was asked to stop by a signal, and stopped after cleaning up.
class Interrupted : public Error {
public:
    Interrupted(int signal, const std::string& message) : Error(message), signal_(signal) {}
    int exit_code() const override { return 128 + signal_; }

private:
    int signal_;
};

/// Throws an error of the same kind as `cause`, so with the same exit code, at `where` with
/// `message`: a file named inside another file that cannot be read stays an I/O error
/// (exit 3), reported at the line that names it.
[[noreturn]] void rethrow_at(const Error& cause, const SourceLocation& where, const std::string& message);

[[noreturn]] void check_failed(const char* condition, const char* file, int line,
                               const std::string& message);

}  // namespace rfd

/// Always-on invariant check: a failure is a bug in rfd, never the user's fault.
#define RFD_CHECK(condition)                                                            \
    do {                                                                                \
        if (!(condition)) ::rfd::check_failed(#condition, __FILE__, __LINE__, "");      \
    } while (false)

#define RFD_CHECK_MSG(condition, message)                                               \
    do {                                                                                \
        if (!(condition)) ::rfd::check_failed(#condition, __FILE__, __LINE__, message); \
    } while (false)

#ifdef NDEBUG
#define RFD_DCHECK(condition) \
    do {                      \
    } while (false)
#else
#define RFD_DCHECK(condition) RFD_CHECK(condition)
#endif
