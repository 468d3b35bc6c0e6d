#include "project/preview.hpp"

#include <cmath>
#include <fstream>
#include <iterator>
#include <system_error>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image_io.hpp"
#include "core/sphere.hpp"

namespace rfd::project {
namespace {

namespace fs = std::filesystem;

std::string read_bytes(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw IoError(SourceLocation{file.string()}, "cannot read");
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

nlohmann::json vector_json(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json optional_json(const std::optional<double>& value) {
    return value ? nlohmann::json(*value) : nlohmann::json(nullptr);
}

// The directory of Debian's three.js (libjs-three), or empty.
fs::path three_folder() {
    std::error_code ec;
    const fs::path folder = "/usr/share/javascript/three";
    return fs::exists(folder / "three.min.js", ec) ? folder : fs::path();
}

void copy_atomically(const fs::path& from, const fs::path& to) {
    write_file_atomically(to, [&](std::ostream& out) { out << read_bytes(from); });
}

}  // namespace

std::string base64(const std::string& bytes) {
    static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((bytes.size() + 2) / 3 * 4);
    for (std::size_t i = 0; i < bytes.size(); i += 3) {
        const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
        std::uint32_t group = 0;
        for (std::size_t k = 0; k < 3; ++k)
            group = (group << 8) | (k < n ? static_cast<unsigned char>(bytes[i + k]) : 0u);
        for (std::size_t k = 0; k < 4; ++k) out += k <= n ? kAlphabet[(group >> (18 - 6 * k)) & 63u] : '=';
    }
    return out;
}

void write_preview_data(const predict::PreviewSet& set, const std::string& design_name, const fs::path& folder) {
    ensure_directory(folder);
    const int columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(set.directions.size()))));
    write_image(folder / "predicted.png", tiled(set.predicted, columns));
    write_image(folder / "relit.png", tiled(set.relit, columns));
    if (!set.predicted_direct.empty()) write_image(folder / "direct.png", tiled(set.predicted_direct, columns));

    nlohmann::json directions = nlohmann::json::array(), triangles = nlohmann::json::array(),
                   planes = nlohmann::json::array(), rims = nlohmann::json::array();
    for (const Eigen::Vector3d& d : set.directions) directions.push_back(vector_json(d));
    for (std::size_t t = 0; t < set.triangles.size(); ++t) {
        triangles.push_back(set.triangles[t]);
        planes.push_back({vector_json(set.edge_planes[t][0]), vector_json(set.edge_planes[t][1]),
                          vector_json(set.edge_planes[t][2])});
    }
    for (const predict::PreviewRim& rim : set.rims)
        rims.push_back({{"phi_deg", rim.phi_deg},
                        {"wrap_over_deg", optional_json(rim.wrap_over_deg)},
                        {"crosstalk_deg", optional_json(rim.crosstalk_deg)}});
    nlohmann::json data = {
        {"design", design_name},
        {"frame", "display: z the display's axis, toward the light"},
        {"max_angle_deg", set.max_angle_deg},
        {"scale", set.scale},
        {"tile", {set.predicted.front().width(), set.predicted.front().height()}},
        {"columns", columns},
        {"directions", directions},
        {"triangles", triangles},
        {"edge_planes", planes},
        {"rims", rims},
        {"predicted", "data:image/png;base64," + base64(read_bytes(folder / "predicted.png"))},
        {"relit", "data:image/png;base64," + base64(read_bytes(folder / "relit.png"))}};
    if (!set.predicted_direct.empty())
        data["predicted_direct"] = "data:image/png;base64," + base64(read_bytes(folder / "direct.png"));
    write_text_file(folder / "data.js",
                    "// Written by rfd simulate preview: what index.html's light control blends.\n"
                    "window.RFD_PREVIEW = " + data.dump() + ";\n");
}

bool write_preview_assets(const fs::path& folder, const std::vector<fs::path>& stls) {
    ensure_directory(folder);
    copy_atomically(fs::path(RFD_PROJECT_ASSETS_DIR) / "preview.js", folder / "preview.js");
    if (!stls.empty()) {
        nlohmann::json parts = nlohmann::json::array();
        for (const fs::path& stl : stls)
            parts.push_back({{"name", stl.stem().string()}, {"stl", base64(read_bytes(stl))}});
        write_text_file(folder / "holder.js", "// The holder's parts as binary STL, base64.\nwindow.RFD_HOLDER = " +
                                                  parts.dump() + ";\n");
    }
    const fs::path three = three_folder();
    if (three.empty()) return false;
    ensure_directory(folder / "vendor");
    copy_atomically(three / "three.min.js", folder / "vendor/three.min.js");
    copy_atomically(three / "examples/js/loaders/STLLoader.js", folder / "vendor/STLLoader.js");
    copy_atomically(three / "examples/js/controls/OrbitControls.js", folder / "vendor/OrbitControls.js");
    std::error_code ec;
    if (fs::exists("/usr/share/doc/libjs-three/copyright", ec))
        copy_atomically("/usr/share/doc/libjs-three/copyright", folder / "vendor/three-copyright.txt");
    return true;
}

}  // namespace rfd::project
