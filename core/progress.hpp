#pragma once
// Progress of long work, on stderr. Silent when stderr is not a terminal or when the user
// asked for --quiet, so logs and pipes stay clean.

#include <atomic>
#include <chrono>
#include <cstddef>
#include <string>

namespace rfd {

class Progress {
public:
    /// `total` units of work described by `label`. Thread-safe advance().
    Progress(std::string label, std::size_t total);
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    void advance(std::size_t units = 1);
    void finish();

    /// Global switch, set once by the CLI from --quiet.
    static void set_quiet(bool quiet);
    static bool enabled();
    /// A one-line remark on stderr ("rfd: note: ..."), unless --quiet: what rfd assumed
    /// about an input, so the user can check it.
    static void note(const std::string& text);

private:
    void draw(std::size_t done);

    std::string label_;
    std::size_t total_;
    std::atomic<std::size_t> done_{0};
    std::atomic<long long> last_draw_ms_{-1000};
    std::chrono::steady_clock::time_point start_;
    bool finished_ = false;
};

}  // namespace rfd
