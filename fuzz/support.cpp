#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <system_error>

#include "fuzz/fuzz.hpp"

namespace rfd::fuzz {
namespace {

std::filesystem::path& scratch_path() {
    static std::filesystem::path path;
    return path;
}

void remove_scratch() {
    std::error_code ec;
    if (!scratch_path().empty()) std::filesystem::remove_all(scratch_path(), ec);
}

}  // namespace

bool verbose = false;

void report(const Error* rejected) {
    if (rejected)
        std::fprintf(stderr, "  rejected (exit %d): %s\n", rejected->exit_code(), rejected->what());
    else
        std::fprintf(stderr, "  accepted\n");
}

const std::filesystem::path& scratch_folder() {
    std::filesystem::path& path = scratch_path();
    if (path.empty()) {
        std::error_code ec;
        const auto base = std::filesystem::temp_directory_path(ec);
        path = (ec ? std::filesystem::path("/tmp") : base) / ("rfd-fuzz-" + std::to_string(::getpid()));
        std::filesystem::create_directories(path);
        std::atexit(remove_scratch);
    }
    return path;
}

void write_bytes(const std::filesystem::path& path, const std::uint8_t* data, std::size_t size) {
    // A new file rather than a truncated one: ext4 flushes a file truncated and written again
    // when it is closed (auto_da_alloc), which made the targets that read files 30 times slower.
    ::unlink(path.c_str());
    std::FILE* file = std::fopen(path.c_str(), "wb");
    if (!file) {
        std::perror(path.c_str());
        std::abort();  // the harness's own failure, not the reader's
    }
    if (size > 0 && std::fwrite(data, 1, size, file) != size) std::abort();
    std::fclose(file);
}

}  // namespace rfd::fuzz
