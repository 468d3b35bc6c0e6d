#include "core/progress.hpp"

#include <cstdio>
#include <mutex>

#include <unistd.h>

namespace rfd {
namespace {
std::atomic<bool> g_quiet{false};
std::mutex g_draw_mutex;
}  // namespace

void Progress::set_quiet(bool quiet) { g_quiet = quiet; }

bool Progress::enabled() { return !g_quiet && isatty(STDERR_FILENO) == 1; }

void Progress::note(const std::string& text) {
    if (!g_quiet) std::fprintf(stderr, "rfd: note: %s\n", text.c_str());
}

Progress::Progress(std::string label, std::size_t total)
    : label_(std::move(label)), total_(total), start_(std::chrono::steady_clock::now()) {}

Progress::~Progress() { finish(); }

void Progress::advance(std::size_t units) {
    const std::size_t done = done_.fetch_add(units) + units;
    if (!enabled()) return;
    const auto now_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                            std::chrono::steady_clock::now() - start_)
                            .count();
    long long last = last_draw_ms_.load();
    // Redraw at most ten times a second; only the thread that wins the exchange draws.
    if (now_ms - last >= 100 && last_draw_ms_.compare_exchange_strong(last, now_ms)) draw(done);
}

void Progress::draw(std::size_t done) {
    std::lock_guard lock(g_draw_mutex);
    const double percent = total_ ? 100.0 * static_cast<double>(done) / static_cast<double>(total_) : 100.0;
    std::fprintf(stderr, "\r%s: %5.1f%% (%zu/%zu)", label_.c_str(), percent, done, total_);
    std::fflush(stderr);
}

void Progress::finish() {
    if (finished_) return;
    finished_ = true;
    if (!enabled()) return;
    draw(done_.load());
    std::fputc('\n', stderr);
}

}  // namespace rfd
