#include "relight/view_set.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <Eigen/LU>

#include "core/error.hpp"
#include "core/files.hpp"

namespace rfd::relight {
namespace {

std::string size_text(const ReflectanceField& field) {
    return std::to_string(field.width()) + " x " + std::to_string(field.height()) + " x " +
           std::to_string(field.channels());
}

}  // namespace

std::vector<ViewEntry> read_view_file(const std::filesystem::path& path) {
    std::ifstream in(path);
    if (!in) throw IoError(SourceLocation{path.string()}, "cannot open view file");
    std::string line;
    int line_number = 0, count_line = 0;
    long declared = -1;
    std::vector<ViewEntry> views;
    while (std::getline(in, line)) {
        ++line_number;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (is_blank_or_comment(line)) continue;
        std::istringstream fields(line);
        if (declared < 0) {
            std::string extra;
            if (!(fields >> declared) || declared < 1 || (fields >> extra))
                throw InputError(line_in(path, line_number),
                                 "expected the view count (a positive integer), got '" + line + "'");
            count_line = line_number;
            continue;
        }
        ViewEntry view;
        view.line = line_number;
        std::vector<double> numbers;
        std::string token;
        if (!(fields >> view.folder))
            throw InputError(line_in(path, line_number), "expected 'folder x y z [9 rotation numbers]'");
        while (fields >> token) {
            char* end = nullptr;
            const double value = std::strtod(token.c_str(), &end);
            if (end == token.c_str() || *end != '\0' || !std::isfinite(value))
                throw InputError(line_in(path, line_number), "'" + token + "' is not a number");
            numbers.push_back(value);
        }
        if (numbers.size() != 3 && numbers.size() != 12)
            throw InputError(line_in(path, line_number),
                             "expected 'folder x y z' or 'folder x y z' and 9 rotation numbers, got " +
                                 std::to_string(numbers.size()) + " number(s)");
        const Eigen::Vector3d d(numbers[0], numbers[1], numbers[2]);
        if (d.norm() < 1e-12)
            throw InputError(line_in(path, line_number), "view direction has zero length");
        view.direction = d.normalized();
        if (!(view.direction.z() > 0.0))
            throw InputError(line_in(path, line_number),
                             "view direction must point to the display's front (z > 0)");
        if (numbers.size() == 12) {
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) view.to_display(r, c) = numbers[3 + 3 * r + c];
            const double error = (view.to_display * view.to_display.transpose() -
                                  Eigen::Matrix3d::Identity()).norm();
            if (!(error < 1e-4) || !(view.to_display.determinant() > 0.0))
                throw InputError(line_in(path, line_number), "the 9 numbers are not a rotation matrix");
        }
        views.push_back(view);
    }
    if (declared < 0) throw InputError(line_in(path, line_number), "empty view file: expected the view count");
    if (static_cast<long>(views.size()) != declared)
        throw InputError(line_in(path, count_line), "the file declares " + std::to_string(declared) +
                                                   " view(s) but lists " + std::to_string(views.size()));
    return views;
}

void write_view_file(const std::filesystem::path& path, const std::vector<ViewEntry>& views) {
    std::ostringstream out;
    out << "# rfd view set: folder, direction toward the camera (display frame),\n"
           "# rotation (row-major) from the view's light frame to the display frame\n";
    out << views.size() << "\n";
    char number[32];
    for (const ViewEntry& view : views) {
        out << view.folder;
        for (int k = 0; k < 3; ++k) {
            std::snprintf(number, sizeof number, " %.17g", view.direction[k]);
            out << number;
        }
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) {
                std::snprintf(number, sizeof number, " %.17g", view.to_display(r, c));
                out << number;
            }
        out << "\n";
    }
    write_text_file(path, out.str());
}

std::filesystem::path view_file_of(const std::filesystem::path& set) {
    if (std::filesystem::is_directory(set)) return set / "views.txt";
    return set;
}

ViewSet read_view_set(const std::filesystem::path& set_path, const ImageWindow& window) {
    ViewSet set;
    set.file = view_file_of(set_path);
    set.views = read_view_file(set.file);
    const std::filesystem::path base = set.file.parent_path();
    for (const ViewEntry& view : set.views) {
        const std::filesystem::path folder = base / view.folder;
        if (!std::filesystem::is_directory(folder))
            throw IoError(line_in(set.file, view.line), "view folder '" + folder.string() + "' does not exist");
        ReflectanceField field = read_field(folder, window);
        if (field.size() == 0)
            throw InputError(line_in(set.file, view.line), "view '" + view.folder + "' has no images");
        for (auto& d : field.directions) d = (view.to_display * d).normalized();
        if (!set.fields.empty()) {
            const ReflectanceField& first = set.fields.front();
            if (field.width() != first.width() || field.height() != first.height() ||
                field.channels() != first.channels())
                throw InputError(line_in(set.file, view.line),
                                 "view '" + view.folder + "' has images of " + size_text(field) +
                                     " but view '" + set.views.front().folder + "' has " + size_text(first) +
                                     " (width x height x channels): all views must match");
        }
        set.fields.push_back(std::move(field));
    }
    return set;
}

}  // namespace rfd::relight
