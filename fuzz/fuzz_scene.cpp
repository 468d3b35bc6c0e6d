// Scene files (scenes/*.toml): parse_scene, with the meshes and textures a scene names
// taken from a folder holding a tiny figure.obj, figure.ply and texture.png.
#include <filesystem>
#include <string>

#include "core/image.hpp"
#include "core/image_io.hpp"
#include "fuzz/fuzz.hpp"
#include "relight/scene.hpp"

using namespace rfd;

namespace {

// A tetrahedron, as OBJ and as ASCII PLY.
constexpr const char* kObj = "v 0 0 0\nv 10 0 0\nv 0 10 0\nv 0 0 10\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
constexpr const char* kPly =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n10 0 0\n0 10 0\n0 0 10\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

const std::filesystem::path& asset_folder() {
    static const std::filesystem::path folder = [] {
        const auto path = fuzz::scratch_folder() / "scene";
        std::filesystem::create_directories(path);
        const std::string obj = kObj, ply = kPly;
        fuzz::write_bytes(path / "figure.obj", reinterpret_cast<const std::uint8_t*>(obj.data()), obj.size());
        fuzz::write_bytes(path / "figure.ply", reinterpret_cast<const std::uint8_t*>(ply.data()), ply.size());
        Image texture(4, 4, 3);
        for (int y = 0; y < 4; ++y)
            for (int x = 0; x < 4; ++x)
                for (int c = 0; c < 3; ++c) texture.at(x, y, c) = static_cast<float>((x + y + c) % 2);
        write_image(path / "texture.png", texture);
        return path;
    }();
    return folder;
}

}  // namespace

RFD_FUZZ_TARGET(scene) { relight::parse_scene(fuzz::text(data, size), "fuzz.toml", asset_folder()); }
