#include "core/files.hpp"

#include <cctype>
#include <fstream>
#include <random>

#include "core/error.hpp"

namespace rfd {

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
    return full.parent_path() /
           (".tmp" + std::to_string(entropy() % 1000000) + "-" + full.filename().string());
}

void move_into_place(const std::filesystem::path& temporary, const std::filesystem::path& target) {
    std::error_code ec;
    std::filesystem::rename(temporary, target, ec);
    if (ec) {
        std::filesystem::remove(temporary, ec);
        throw IoError(SourceLocation{target.string()}, "cannot move the finished file into place");
    }
}

void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write) {
    namespace fs = std::filesystem;
    const fs::path temporary = temporary_sibling(path);
    std::error_code ec;
    {
        std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
        if (!out) throw IoError(SourceLocation{path.string()}, "cannot write: permission denied");
        try {
            write(out);
        } catch (...) {
            out.close();
            fs::remove(temporary, ec);
            throw;
        }
        out.flush();
        if (!out) {
            out.close();
            fs::remove(temporary, ec);
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
    if (!path_.empty()) {
        std::error_code ec;
        std::filesystem::remove(path_, ec);
    }
}

bool is_blank_or_comment(const std::string& line) {
    for (const char c : line) {
        if (c == '#') return true;
        if (!std::isspace(static_cast<unsigned char>(c))) return false;
    }
    return true;
}

}  // namespace rfd
