#pragma once
// Fuzz targets: one per reader of user input (HACKING.md, "Fuzzing").
//
// A target hands the bytes it is given to one reader, as the program would. Bad input must
// end in an InputError or IoError, the message a user sees with exit code 2 or 3; anything
// else that leaves the target is a finding: another exception (std::bad_alloc, a plain
// rfd::Error), an abort (a failed RFD_CHECK), a sanitizer report, or a hang. The same
// target file builds two ways:
//  - with clang's libFuzzer (the `fuzz` preset, RFD_FUZZ_ENGINE=libfuzzer): RFD_FUZZ_TARGET
//    defines LLVMFuzzerTestOneInput, one coverage-guided program per target, rfd_fuzz_NAME;
//  - into one program with fuzz/driver.cpp (the `asan` preset, CI): rfd_fuzz NAME runs the
//    seed corpus and seeded mutations of it, with no compiler support needed.
//
// Example: RFD_FUZZ_TARGET(printer) { print::parse_printer(std::string(text(data, size)), "fuzz.toml"); }

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string_view>

#include "core/error.hpp"

namespace rfd::fuzz {

using Entry = int (*)(const std::uint8_t* data, std::size_t size);

/// Adds a target to the driver's table; returns true (for a static initialiser).
bool register_target(const char* name, Entry entry);

/// rfd_fuzz --verbose: each input's outcome on stderr, accepted or the error's message.
extern bool verbose;
void report(const Error* rejected);

/// The bytes as text.
inline std::string_view text(const std::uint8_t* data, std::size_t size) {
    return {reinterpret_cast<const char*>(data), size};
}

/// A folder of this process's own under the temporary directory, created on first use and
/// removed at exit: targets whose reader takes a path write their input there.
const std::filesystem::path& scratch_folder();

/// Writes the bytes to `path`, replacing it.
void write_bytes(const std::filesystem::path& path, const std::uint8_t* data, std::size_t size);

}  // namespace rfd::fuzz

// Both ways run the target once on an empty input before the first real one: what a
// process does once (loading OpenImageIO, writing a target's fixed files, about a second
// under the sanitizers) is not a hang of the first input.
#ifdef RFD_FUZZ_LIBFUZZER
#define RFD_FUZZ_EXPORT(name)                                                              \
    extern "C" int LLVMFuzzerInitialize(int*, char***) { return rfd_fuzz_entry(nullptr, 0); } \
    extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {    \
        return rfd_fuzz_entry(data, size);                                                 \
    }
#else
#define RFD_FUZZ_EXPORT(name)                                                              \
    [[maybe_unused]] static const bool rfd_fuzz_registered = ::rfd::fuzz::register_target(#name, rfd_fuzz_entry);
#endif

/// Defines target `name`; the body follows, with `data` and `size` in scope. The errors a
/// user may cause are caught here; everything else leaves the target.
#define RFD_FUZZ_TARGET(name)                                                              \
    static void rfd_fuzz_body(const std::uint8_t* data, std::size_t size);                 \
    static int rfd_fuzz_entry(const std::uint8_t* data, std::size_t size) {                \
        try {                                                                              \
            rfd_fuzz_body(data, size);                                                     \
            if (::rfd::fuzz::verbose) ::rfd::fuzz::report(nullptr);                        \
        } catch (const ::rfd::InputError& error) {                                         \
            if (::rfd::fuzz::verbose) ::rfd::fuzz::report(&error);                         \
        } catch (const ::rfd::IoError& error) {                                            \
            if (::rfd::fuzz::verbose) ::rfd::fuzz::report(&error);                         \
        }                                                                                  \
        return 0;                                                                          \
    }                                                                                      \
    RFD_FUZZ_EXPORT(name)                                                                  \
    static void rfd_fuzz_body(const std::uint8_t* data, std::size_t size)
