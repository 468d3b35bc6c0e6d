// rfd_fuzz: the fuzz targets (fuzz/fuzz.hpp) without libFuzzer. Runs every seed, then
// mutations of them drawn from a seeded generator (the same inputs on every machine), and
// stops at the first finding with its input saved. What CI runs, under ASan and UBSan.
//
//   rfd_fuzz TARGET [--runs N] [--seed S] [--dict FILE]... [--max-len N] [--timeout SEC]
//            [--max-seconds SEC] [--artifacts DIR] [--verbose] PATH...
//   rfd_fuzz --list
//
// PATH: seed files, or folders of them. --runs counts every input, seeds included (default:
// the seeds alone, which reproduces a saved finding: rfd_fuzz TARGET crash-TARGET-...).
// --verbose prints each input's outcome: accepted, or the error a user would see.
// A finding is an exception other than InputError or IoError leaving the target, a signal
// (a failed RFD_CHECK aborts), a sanitizer report, or an input running longer than
// --timeout (default 1 s of CPU time, or ten times that of wall-clock time). Exit code 0
// when there was none, 1 when there was, 2 on a wrong command line.
//
// A mutation is one to four edits of a seed, each one of: flip a bit, set a byte (to a
// random or a boundary value), insert or erase bytes, copy a span elsewhere, insert a
// dictionary token (anywhere, or at the start of a line, or repeated up to 500 times),
// replace a word or a number by a token or a boundary number, repeat or delete a line,
// splice two seeds, write a boundary 32-bit integer (binary headers), truncate.

#include <cxxabi.h>
#include <time.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <typeinfo>
#include <utility>
#include <vector>

#include "fuzz/fuzz.hpp"

extern "C" void __sanitizer_set_death_callback(void (*callback)(void)) __attribute__((weak));

namespace rfd::fuzz {

std::map<std::string, Entry>& targets() {
    static std::map<std::string, Entry> table;
    return table;
}

bool register_target(const char* name, Entry entry) {
    targets()[name] = entry;
    return true;
}

namespace {

// --- Saving the input that was running when the process dies --------------------------

// Set before each input; read by the signal handlers, so plain data only.
const std::string* g_input = nullptr;
char g_artifact[4096];      // path the input is saved to
double g_timeout = 1.0;

void write_all(int fd, const char* data, std::size_t size) {
    while (size > 0) {
        const ssize_t n = ::write(fd, data, size);
        if (n <= 0) return;
        data += n;
        size -= static_cast<std::size_t>(n);
    }
}

void say(const char* text) { write_all(2, text, std::strlen(text)); }

// Async-signal-safe: open, write, close.
void save_input() {
    if (!g_input) return;
    const std::string* input = g_input;
    g_input = nullptr;  // once
    const int fd = ::open(g_artifact, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) return;
    write_all(fd, input->data(), input->size());
    ::close(fd);
    say("\nrfd_fuzz: the input is saved in ");
    say(g_artifact);
    say("\n");
}

void on_fatal_signal(int signal_number) {
    save_input();
    ::signal(signal_number, SIG_DFL);
    ::raise(signal_number);
}

void on_timeout(int) {
    say("\nrfd_fuzz: finding: an input ran longer than the timeout (a hang)\n");
    save_input();
    ::_exit(1);
}

// --timeout counts the process's CPU time (ITIMER_PROF), so that a machine busy with other
// work does not turn a slow moment into a hang; ten times as much wall-clock time
// (ITIMER_REAL) catches an input that blocks without computing. 0 disarms both.
void arm_timer(double seconds) {
    const auto set = [](int which, double s) {
        itimerval timer{};
        timer.it_value.tv_sec = static_cast<time_t>(s);
        timer.it_value.tv_usec = static_cast<suseconds_t>((s - static_cast<double>(timer.it_value.tv_sec)) * 1e6);
        ::setitimer(which, &timer, nullptr);
    };
    set(ITIMER_PROF, seconds);
    set(ITIMER_REAL, 10 * seconds);
}

void install_handlers() {
    struct sigaction action {};
    action.sa_handler = on_fatal_signal;
    sigemptyset(&action.sa_mask);
    ::sigaction(SIGABRT, &action, nullptr);  // RFD_CHECK, std::terminate, abort_on_error
    if (__sanitizer_set_death_callback) {
        // The sanitizers report SIGSEGV and the like themselves, then call this.
        __sanitizer_set_death_callback(save_input);
    } else {
        for (int s : {SIGSEGV, SIGBUS, SIGFPE, SIGILL}) ::sigaction(s, &action, nullptr);
    }
    action.sa_handler = on_timeout;
    ::sigaction(SIGPROF, &action, nullptr);
    ::sigaction(SIGALRM, &action, nullptr);
}

// --- Deterministic mutations ----------------------------------------------------------

// splitmix64: a tiny generator whose sequence is the same everywhere (unlike the
// standard distributions).
struct Random {
    std::uint64_t state;
    std::uint64_t next() {
        std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
        return z ^ (z >> 31);
    }
    /// Uniform in [0, n), n > 0.
    std::size_t below(std::size_t n) { return static_cast<std::size_t>(next() % n); }
};

const char* const kBoundaryNumbers[] = {
    "0", "-0", "1", "-1", "2", "0.5", "1e308", "-1e308", "1e-308", "5e-324", "1e999", "inf", "-inf",
    "nan", "+nan", "-nan", "2147483647", "2147483648", "-2147483649", "4294967296", "9223372036854775807",
    "9223372036854775808", "-9223372036854775808", "65504", "65505", "16384", "16385", "100000", "100001",
    "1e9", "1e10", "1e30", "180", "90", "360", "0x7fffffff", "0b1", "0o7", "1_000", "1.", ".5", "1e", "-",
};

const std::uint32_t kBoundaryWords[] = {0u, 1u, 0x7fu, 0x80u, 0xffu, 0x7fffu, 0x8000u, 0xffffu, 0x10000u,
                                        0x7fffffffu, 0x80000000u, 0xffffffffu, 0xfffffffeu, 0x40000000u};

const unsigned char kBoundaryBytes[] = {0, 1, 0x7f, 0x80, 0xff, '\n', '\r', '"', '\'', '[', ']', '=', '.',
                                        '#', '-', '\\', ' ', '{', '}', ','};

bool is_word_char(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '+' || c == '-';
}

bool is_number_char(char c) {
    return std::isdigit(static_cast<unsigned char>(c)) || c == '.' || c == '+' || c == '-' || c == 'e' || c == 'E';
}

// The span [begin, end) of characters around `at` that satisfy `inside`.
std::pair<std::size_t, std::size_t> span_around(const std::string& s, std::size_t at, bool (*inside)(char)) {
    std::size_t begin = at, end = at;
    while (begin > 0 && inside(s[begin - 1])) --begin;
    while (end < s.size() && inside(s[end])) ++end;
    return {begin, end};
}

class Mutator {
public:
    Mutator(const std::vector<std::string>& seeds, const std::vector<std::string>& tokens, std::size_t max_len,
            std::uint64_t seed)
        : seeds_(seeds), tokens_(tokens), max_len_(max_len), random_{seed} {}

    std::string next() {
        std::string s = seeds_[random_.below(seeds_.size())];
        const std::size_t edits = 1 + random_.below(4);
        for (std::size_t k = 0; k < edits; ++k) edit(s);
        if (s.size() > max_len_) s.resize(max_len_);
        return s;
    }

private:
    std::string token() {
        if (!tokens_.empty() && random_.below(4) != 0) return tokens_[random_.below(tokens_.size())];
        return kBoundaryNumbers[random_.below(std::size(kBoundaryNumbers))];
    }
    std::size_t position(const std::string& s) { return random_.below(s.size() + 1); }
    // Start of a line: 0 or just after a '\n'.
    std::size_t line_start(const std::string& s) {
        const std::size_t at = s.rfind('\n', position(s));
        return at == std::string::npos ? 0 : at + 1;
    }

    void edit(std::string& s) {
        switch (random_.below(16)) {
            case 0:  // flip a bit
                if (!s.empty()) s[random_.below(s.size())] ^= static_cast<char>(1u << random_.below(8));
                break;
            case 1:  // a random byte
                if (!s.empty()) s[random_.below(s.size())] = static_cast<char>(random_.below(256));
                break;
            case 2:  // a boundary byte
                if (!s.empty())
                    s[random_.below(s.size())] = static_cast<char>(kBoundaryBytes[random_.below(std::size(kBoundaryBytes))]);
                break;
            case 3: {  // insert random bytes
                std::string bytes(1 + random_.below(4), '\0');
                for (char& c : bytes) c = static_cast<char>(random_.below(256));
                s.insert(position(s), bytes);
                break;
            }
            case 4: {  // erase a span
                if (s.empty()) break;
                const std::size_t at = random_.below(s.size());
                s.erase(at, 1 + random_.below(std::min<std::size_t>(64, s.size() - at)));
                break;
            }
            case 5: {  // copy a span elsewhere
                if (s.empty()) break;
                const std::size_t at = random_.below(s.size());
                const std::string span = s.substr(at, 1 + random_.below(std::min<std::size_t>(128, s.size() - at)));
                s.insert(position(s), span);
                break;
            }
            case 6: s.insert(position(s), token()); break;
            case 7: s.insert(line_start(s), token()); break;
            case 8: {  // repeat a token: deep keys, deep nesting, long lines
                const std::string t = token();
                std::string repeated;
                for (std::size_t n = 2 + random_.below(499); n > 0 && repeated.size() < max_len_; --n) repeated += t;
                s.insert(position(s), repeated);
                break;
            }
            case 9:
            case 10: {  // replace a word (case 9) or a number (case 10)
                if (s.empty()) break;
                const auto [begin, end] = span_around(s, random_.below(s.size()), random_.below(2) == 0 ? is_word_char : is_number_char);
                const std::string t = random_.below(2) == 0 ? std::string(kBoundaryNumbers[random_.below(std::size(kBoundaryNumbers))])
                                                            : token();
                s.replace(begin, end - begin, t);
                break;
            }
            case 11: {  // repeat a line
                const std::size_t begin = line_start(s);
                std::size_t end = s.find('\n', begin);
                end = end == std::string::npos ? s.size() : end + 1;
                const std::string line = s.substr(begin, end - begin);
                std::string repeated;
                for (std::size_t n = 1 + random_.below(64); n > 0 && repeated.size() < max_len_; --n) repeated += line;
                s.insert(begin, repeated);
                break;
            }
            case 12: {  // delete a line
                const std::size_t begin = line_start(s);
                const std::size_t end = s.find('\n', begin);
                s.erase(begin, end == std::string::npos ? std::string::npos : end + 1 - begin);
                break;
            }
            case 13: {  // splice: the start of this input, the end of another
                const std::string& other = seeds_[random_.below(seeds_.size())];
                s = s.substr(0, position(s)) + other.substr(random_.below(other.size() + 1));
                break;
            }
            case 14: {  // a boundary 32-bit integer, little-endian (binary headers)
                if (s.size() < 4) break;
                std::uint32_t w = kBoundaryWords[random_.below(std::size(kBoundaryWords))];
                if (random_.below(2) == 0) w += static_cast<std::uint32_t>(random_.below(3)) - 1u;
                const std::size_t at = random_.below(s.size() - 3);
                for (int b = 0; b < 4; ++b) s[at + static_cast<std::size_t>(b)] = static_cast<char>((w >> (8 * b)) & 0xff);
                break;
            }
            default:  // truncate
                s.resize(position(s));
                break;
        }
    }

    const std::vector<std::string>& seeds_;
    const std::vector<std::string>& tokens_;
    std::size_t max_len_;
    Random random_;
};

// The readable name of an exception's type.
std::string type_name(const std::type_info& type) {
    int status = 0;
    char* demangled = abi::__cxa_demangle(type.name(), nullptr, nullptr, &status);
    std::string name = status == 0 && demangled ? demangled : type.name();
    std::free(demangled);
    return name;
}

// --- Files ------------------------------------------------------------------------------

std::string read_whole(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

// libFuzzer's dictionary format: one "token" a line, optionally name="token"; \\, \" and
// \xNN escapes; '#' comments.
std::vector<std::string> read_dictionary(const std::filesystem::path& path) {
    std::ifstream in(path);
    if (!in) {
        std::fprintf(stderr, "rfd_fuzz: cannot open dictionary %s\n", path.c_str());
        std::exit(2);
    }
    std::vector<std::string> tokens;
    for (std::string line; std::getline(in, line);) {
        const std::size_t open = line.find('"');
        const std::size_t close = line.rfind('"');
        if (line.empty() || line[0] == '#' || open == std::string::npos || close <= open) continue;
        std::string token;
        for (std::size_t i = open + 1; i < close; ++i) {
            if (line[i] != '\\' || i + 1 >= close) {
                token += line[i];
            } else if (line[i + 1] == 'x' && i + 3 < close) {
                token += static_cast<char>(std::stoi(line.substr(i + 2, 2), nullptr, 16));
                i += 3;
            } else {
                token += line[++i];
            }
        }
        tokens.push_back(token);
    }
    return tokens;
}

std::vector<std::filesystem::path> seed_files(const std::vector<std::filesystem::path>& paths) {
    std::vector<std::filesystem::path> files;
    for (const auto& path : paths) {
        if (std::filesystem::is_directory(path)) {
            std::vector<std::filesystem::path> in_folder;
            for (const auto& entry : std::filesystem::directory_iterator(path))
                if (entry.is_regular_file()) in_folder.push_back(entry.path());
            std::sort(in_folder.begin(), in_folder.end());  // the same order everywhere
            files.insert(files.end(), in_folder.begin(), in_folder.end());
        } else if (std::filesystem::is_regular_file(path)) {
            files.push_back(path);
        } else {
            std::fprintf(stderr, "rfd_fuzz: no such seed file or folder: %s\n", path.c_str());
            std::exit(2);
        }
    }
    return files;
}

[[noreturn]] void usage(const char* message) {
    std::fprintf(stderr,
                 "rfd_fuzz: %s\nusage: rfd_fuzz TARGET [--runs N] [--seed S] [--dict FILE]... [--max-len N]\n"
                 "                [--timeout SEC] [--max-seconds SEC] [--artifacts DIR] [--verbose] PATH...\n"
                 "       rfd_fuzz --list\n",
                 message);
    std::exit(2);
}

// The process's CPU time so far, all threads, in seconds: what --timeout counts.
double cpu_seconds() {
    timespec t{};
    ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double elapsed(std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

int run(int argc, char** argv) {
    if (argc >= 2 && std::string(argv[1]) == "--list") {
        for (const auto& [name, entry] : targets()) std::printf("%s\n", name.c_str());
        return 0;
    }
    if (argc < 3) usage("expected a target and seed paths");
    const std::string name = argv[1];
    if (!targets().count(name)) usage(("no target '" + name + "' (rfd_fuzz --list)").c_str());
    const Entry entry = targets()[name];

    long long runs = 0;
    std::uint64_t seed = 1;
    std::size_t max_len = 0;
    double max_seconds = 0.0;
    std::filesystem::path artifacts = ".";
    std::vector<std::string> tokens;
    std::vector<std::filesystem::path> paths;
    for (int i = 2; i < argc; ++i) {
        const std::string arg = argv[i];
        const auto value = [&]() -> std::string {
            if (i + 1 >= argc) usage((arg + " needs a value").c_str());
            return argv[++i];
        };
        try {
            if (arg == "--runs") runs = std::stoll(value());
            else if (arg == "--seed") seed = std::stoull(value());
            else if (arg == "--max-len") max_len = std::stoull(value());
            else if (arg == "--timeout") g_timeout = std::stod(value());
            else if (arg == "--max-seconds") max_seconds = std::stod(value());
            else if (arg == "--artifacts") artifacts = value();
            else if (arg == "--verbose") verbose = true;
            else if (arg == "--dict") {
                const auto more = read_dictionary(value());
                tokens.insert(tokens.end(), more.begin(), more.end());
            } else if (arg.rfind("--", 0) == 0) usage(("unknown option " + arg).c_str());
            else paths.emplace_back(arg);
        } catch (const std::logic_error&) {
            usage((arg + ": expected a number").c_str());
        }
    }
    if (paths.empty()) usage("expected seed paths");
    std::vector<std::string> seeds;
    std::size_t longest = 0;
    for (const auto& file : seed_files(paths)) {
        seeds.push_back(read_whole(file));
        longest = std::max(longest, seeds.back().size());
    }
    if (seeds.empty()) usage("no seed files");
    if (max_len == 0) max_len = std::max<std::size_t>(4096, 2 * longest);
    runs = std::max<long long>(runs, static_cast<long long>(seeds.size()));

    install_handlers();
    const bool quiet_warm_up = !std::exchange(verbose, false);
    entry(nullptr, 0);  // warm-up (fuzz/fuzz.hpp)
    verbose = !quiet_warm_up;
    Mutator mutator(seeds, tokens, max_len, seed);
    const auto start = std::chrono::steady_clock::now();
    double slowest = 0.0, slowest_wall = 0.0;  // CPU seconds, and wall-clock seconds
    long long slowest_at = 0, done = 0;
    std::string input;
    for (; done < runs; ++done) {
        if (max_seconds > 0.0 && elapsed(start) > max_seconds) break;
        input = done < static_cast<long long>(seeds.size()) ? seeds[static_cast<std::size_t>(done)] : mutator.next();
        std::snprintf(g_artifact, sizeof g_artifact, "%s/crash-%s-%lld", artifacts.c_str(), name.c_str(), done);
        g_input = &input;
        if (verbose) std::fprintf(stderr, "input %lld (%zu bytes):\n", done, input.size());
        const auto begin = std::chrono::steady_clock::now();
        const double begin_cpu = cpu_seconds();
        arm_timer(g_timeout);
        try {
            entry(reinterpret_cast<const std::uint8_t*>(input.data()), input.size());
        } catch (const std::exception& error) {
            arm_timer(0.0);
            std::fprintf(stderr, "\nrfd_fuzz: finding: input %lld of %s: uncaught %s: %s\n", done, name.c_str(),
                         type_name(typeid(error)).c_str(), error.what());
            save_input();
            return 1;
        } catch (...) {
            arm_timer(0.0);
            std::fprintf(stderr, "\nrfd_fuzz: finding: input %lld of %s: uncaught exception of unknown type\n", done,
                         name.c_str());
            save_input();
            return 1;
        }
        arm_timer(0.0);
        g_input = nullptr;
        const double seconds = cpu_seconds() - begin_cpu;
        slowest_wall = std::max(slowest_wall, elapsed(begin));
        if (seconds > slowest) {
            slowest = seconds;
            slowest_at = done;
        }
        if ((done + 1) % 10000 == 0)
            std::fprintf(stderr, "rfd_fuzz %s: %lld inputs, %.1f s\n", name.c_str(), done + 1, elapsed(start));
    }
    const double total = elapsed(start);
    std::printf("rfd_fuzz %s: %lld inputs (%zu seeds, %lld mutations, seed %llu) in %.1f s, %.0f/s; "
                "slowest %.3f s of CPU (input %lld), %.3f s of wall-clock time; no finding\n",
                name.c_str(), done, seeds.size(), done - static_cast<long long>(seeds.size()),
                static_cast<unsigned long long>(seed), total, static_cast<double>(done) / std::max(total, 1e-9), slowest,
                slowest_at, slowest_wall);
    return 0;
}

}  // namespace
}  // namespace rfd::fuzz

int main(int argc, char** argv) { return rfd::fuzz::run(argc, argv); }
