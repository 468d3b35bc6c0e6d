#include "core/files.hpp"

#include <fstream>
#include <random>

#include "core/error.hpp"

namespace rfd {

void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write) {
    namespace fs = std::filesystem;
    const fs::path target = path.has_parent_path() ? path : fs::path(".") / path;
    std::error_code ec;
    if (!fs::is_directory(target.parent_path(), ec))
        throw IoError(SourceLocation{path.string()},
                      "cannot write: directory '" + target.parent_path().string() +
                          "' does not exist");
    // A per-process random suffix keeps concurrent writers of the same target apart.
    std::random_device entropy;
    const fs::path temporary =
        target.parent_path() /
        ("." + target.filename().string() + ".tmp" + std::to_string(entropy() % 1000000));
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
    fs::rename(temporary, target, ec);
    if (ec) {
        fs::remove(temporary, ec);
        throw IoError(SourceLocation{path.string()}, "cannot move the finished file into place");
    }
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

}  // namespace rfd
