#include "core/files.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>

#include "core/error.hpp"

namespace rfd {
namespace {

// The temporary files being written, for a signal handler to remove. A handler may only
// read lock-free memory and call async-signal-safe functions (unlink, _exit), so the paths
// sit in fixed slots, each claimed and released with an atomic state.
struct TemporarySlot {
    enum State : int { free, busy, holding };
    std::atomic<int> state{free};
    char path[PATH_MAX];
};
static_assert(std::atomic<int>::is_always_lock_free);
std::array<TemporarySlot, 64> temporaries;

void remember_temporary(const std::filesystem::path& path) {
    const std::string& text = path.native();
    if (text.size() >= PATH_MAX) return;
    for (TemporarySlot& slot : temporaries) {
        int expected = TemporarySlot::free;
        if (!slot.state.compare_exchange_strong(expected, TemporarySlot::busy)) continue;
        std::memcpy(slot.path, text.c_str(), text.size() + 1);
        slot.state.store(TemporarySlot::holding);
        return;
    }
    // Every slot taken: this file is not removed on a signal. rfd writes a few files at a
    // time, never 64.
}

void forget_temporary(const std::filesystem::path& path) {
    for (TemporarySlot& slot : temporaries) {
        int expected = TemporarySlot::holding;
        if (slot.state.load() != TemporarySlot::holding || path.native() != slot.path) continue;
        if (slot.state.compare_exchange_strong(expected, TemporarySlot::busy)) {
            slot.state.store(TemporarySlot::free);
            return;
        }
    }
}

extern "C" void remove_temporaries_and_exit(int signal) {
    for (TemporarySlot& slot : temporaries)
        if (slot.state.load() == TemporarySlot::holding) unlink(slot.path);
    _exit(128 + signal);
}

}  // namespace

void remove_temporaries_on_signals() {
    for (const int signal : {SIGINT, SIGTERM, SIGHUP, SIGXFSZ}) {
        struct sigaction current {};
        if (sigaction(signal, nullptr, &current) == 0 && current.sa_handler == SIG_IGN) continue;
        struct sigaction action {};
        action.sa_handler = remove_temporaries_and_exit;
        sigemptyset(&action.sa_mask);
        sigaction(signal, &action, nullptr);
    }
}

void remove_temporary(const std::filesystem::path& temporary) {
    std::error_code ec;
    std::filesystem::remove(temporary, ec);
    forget_temporary(temporary);
}

std::filesystem::path temporary_sibling(const std::filesystem::path& target) {
    namespace fs = std::filesystem;
    const fs::path full = target.has_parent_path() ? target : fs::path(".") / target;
    std::error_code ec;
    if (!fs::is_directory(full.parent_path(), ec))
        throw IoError(SourceLocation{target.string()},
                      "cannot write: directory '" + full.parent_path().string() +
                          "' does not exist");
    // A random prefix keeps concurrent writers of the same target apart; the name keeps
    // its extension.
    std::random_device entropy;
    fs::path temporary = full.parent_path() / (".tmp" + std::to_string(entropy() % 1000000) + "-" + full.filename().string());
    remember_temporary(temporary);
    return temporary;
}

void move_into_place(const std::filesystem::path& temporary, const std::filesystem::path& target) {
    // A full disk may only say so when the data is forced out: never rename a file whose
    // bytes did not all reach the disk.
    const int fd = open(temporary.c_str(), O_RDONLY | O_CLOEXEC);
    const bool synced = fd >= 0 && fsync(fd) == 0;
    if (fd >= 0) close(fd);
    if (!synced) {
        remove_temporary(temporary);
        throw IoError(SourceLocation{target.string()}, "writing failed (disk full?)");
    }
    std::error_code ec;
    std::filesystem::rename(temporary, target, ec);
    if (ec) {
        remove_temporary(temporary);
        throw IoError(SourceLocation{target.string()}, "cannot move the finished file into place");
    }
    forget_temporary(temporary);
}

void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write) {
    namespace fs = std::filesystem;
    const fs::path temporary = temporary_sibling(path);
    {
        std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
        if (!out) {
            remove_temporary(temporary);
            throw IoError(SourceLocation{path.string()}, "cannot write: permission denied");
        }
        try {
            write(out);
        } catch (...) {
            out.close();
            remove_temporary(temporary);
            throw;
        }
        out.flush();
        if (!out) {
            out.close();
            remove_temporary(temporary);
            throw IoError(SourceLocation{path.string()}, "write failed (disk full?)");
        }
    }
    move_into_place(temporary, path);
}

void write_text_file(const std::filesystem::path& path, const std::string& text) {
    write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

void ensure_directory(const std::filesystem::path& dir) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec || !std::filesystem::is_directory(dir))
        throw IoError(SourceLocation{dir.string()}, "cannot create directory: " + ec.message());
}

TemporaryFile::~TemporaryFile() {
    if (!path_.empty()) remove_temporary(path_);
}

bool is_blank_or_comment(const std::string& line) {
    for (const char c : line) {
        if (c == '#') return true;
        if (!std::isspace(static_cast<unsigned char>(c))) return false;
    }
    return true;
}

ExclusiveLock::ExclusiveLock(const std::filesystem::path& file, const std::string& busy_message) {
    descriptor_ = open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (descriptor_ < 0) throw IoError("cannot create the lock file " + file.string() + ": " + std::strerror(errno));
    if (flock(descriptor_, LOCK_EX | LOCK_NB) != 0) {
        const int error = errno;
        close(descriptor_);
        if (error == EWOULDBLOCK) throw IoError(busy_message);
        throw IoError("cannot lock " + file.string() + ": " + std::strerror(error));
    }
}

ExclusiveLock::~ExclusiveLock() {
    if (descriptor_ >= 0) close(descriptor_);  // closing releases the lock
}

SourceLocation line_in(const std::filesystem::path& path, int line) { return SourceLocation{path.string(), line, 0, ""}; }

}  // namespace rfd

namespace rfd {

std::string read_text_file(const std::filesystem::path& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw IoError(SourceLocation{path.string()}, "cannot open: no such file");
    // rfd's input files are a few kilobytes; a large one is not one of them.
    constexpr std::uintmax_t kMaxBytes = 16 << 20;
    if (std::filesystem::file_size(path, ec) > kMaxBytes)
        throw InputError(SourceLocation{path.string()}, "larger than 16 MB: not an rfd input file");
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    if (!in) throw IoError(SourceLocation{path.string()}, "cannot read");
    return text.str();
}

void raise_open_file_limit(std::size_t files) {
    rlimit limit{};
    if (getrlimit(RLIMIT_NOFILE, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY || limit.rlim_cur >= files) return;
    limit.rlim_cur = limit.rlim_max == RLIM_INFINITY ? files : std::min<rlim_t>(files, limit.rlim_max);
    setrlimit(RLIMIT_NOFILE, &limit);  // best effort: opening the files says what failed
}

}  // namespace rfd
