#include "project/preview.hpp"

#include <cmath>
#include <fstream>
#include <iterator>
#include <system_error>

#include <nlohmann/json.hpp>

#include "core/json.hpp"
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

void to_json(nlohmann::json& json, const PreviewData& data) {
    nlohmann::json rims = nlohmann::json::array();
    for (const PreviewData::Rim& rim : data.rims)
        rims.push_back({{"phi_deg", rim.phi_deg},
                        {"wrap_over_deg", json_or_null(rim.wrap_over_deg)},
                        {"crosstalk_deg", json_or_null(rim.crosstalk_deg)}});
    json = {{"design", data.design},
            {"frame", data.frame},
            {"max_angle_deg", data.max_angle_deg},
            {"scale", data.scale},
            {"tile", data.tile},
            {"columns", data.columns},
            {"directions", data.directions},
            {"triangles", data.triangles},
            {"edge_planes", data.edge_planes},
            {"rims", rims},
            {"predicted", data.predicted},
            {"relit", data.relit}};
    if (data.predicted_direct) json["predicted_direct"] = *data.predicted_direct;
}

void from_json(const nlohmann::json& json, PreviewData& data) {
    json.at("design").get_to(data.design);
    json.at("frame").get_to(data.frame);
    json.at("max_angle_deg").get_to(data.max_angle_deg);
    json.at("scale").get_to(data.scale);
    json.at("tile").get_to(data.tile);
    json.at("columns").get_to(data.columns);
    json.at("directions").get_to(data.directions);
    json.at("triangles").get_to(data.triangles);
    json.at("edge_planes").get_to(data.edge_planes);
    data.rims.clear();
    for (const nlohmann::json& rim : json.at("rims")) {
        const auto optional = [&](const char* key) {
            return rim.at(key).is_null() ? std::nullopt : std::optional<double>(rim.at(key).get<double>());
        };
        data.rims.push_back({rim.at("phi_deg").get<double>(), optional("wrap_over_deg"), optional("crosstalk_deg")});
    }
    json.at("predicted").get_to(data.predicted);
    json.at("relit").get_to(data.relit);
    data.predicted_direct.reset();
    if (json.contains("predicted_direct")) data.predicted_direct = json.at("predicted_direct").get<std::string>();
}

namespace {

constexpr const char* kDataPrefix =
    "// Written by rfd simulate preview: what index.html's light control blends.\nwindow.RFD_PREVIEW = ";

std::array<double, 3> array_of(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

std::string png_uri(const fs::path& file) { return "data:image/png;base64," + base64(read_bytes(file)); }

}  // namespace

PreviewData write_preview_data(const predict::PreviewSet& set, const std::string& design_name, const fs::path& folder) {
    ensure_directory(folder);
    PreviewData data;
    data.design = design_name;
    data.max_angle_deg = set.max_angle_deg;
    data.scale = set.scale;
    data.tile = {set.predicted.front().width(), set.predicted.front().height()};
    data.columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(set.directions.size()))));
    write_image(folder / "predicted.png", tiled(set.predicted, data.columns));
    write_image(folder / "relit.png", tiled(set.relit, data.columns));
    if (!set.predicted_direct.empty()) write_image(folder / "direct.png", tiled(set.predicted_direct, data.columns));
    for (const Eigen::Vector3d& d : set.directions) data.directions.push_back(array_of(d));
    data.triangles = set.triangles;
    for (const auto& planes : set.edge_planes)
        data.edge_planes.push_back({array_of(planes[0]), array_of(planes[1]), array_of(planes[2])});
    for (const predict::PreviewRim& rim : set.rims) data.rims.push_back({rim.phi_deg, rim.wrap_over_deg, rim.crosstalk_deg});
    data.predicted = png_uri(folder / "predicted.png");
    data.relit = png_uri(folder / "relit.png");
    if (!set.predicted_direct.empty()) data.predicted_direct = png_uri(folder / "direct.png");
    write_text_file(folder / "data.js", kDataPrefix + nlohmann::json(data).dump() + ";\n");
    return data;
}

PreviewData read_preview_data(const fs::path& file) {
    const std::string text = read_bytes(file);
    const std::string prefix = kDataPrefix;
    if (text.size() < prefix.size() + 2 || text.compare(0, prefix.size(), prefix) != 0 || !text.ends_with(";\n"))
        throw InputError(SourceLocation{file.string()}, "not a preview's data.js (window.RFD_PREVIEW = {...};)");
    try {
        return nlohmann::json::parse(text.substr(prefix.size(), text.size() - prefix.size() - 2)).get<PreviewData>();
    } catch (const nlohmann::json::exception& e) {
        throw InputError(SourceLocation{file.string()}, std::string("not a preview's data.js: ") + e.what());
    }
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
