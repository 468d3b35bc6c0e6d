#pragma once
// The folder the scene targets take meshes and textures from: a tiny figure.obj,
// figure.ply (a tetrahedron) and texture.png (4 x 4), written once per process.

#include <filesystem>
#include <string>

#include "core/image.hpp"
#include "core/image_io.hpp"
#include "fuzz/fuzz.hpp"

namespace rfd::fuzz {

// A tetrahedron, as OBJ and as ASCII PLY.
inline constexpr const char* kObj = "v 0 0 0\nv 10 0 0\nv 0 10 0\nv 0 0 10\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
inline constexpr const char* kPly =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n10 0 0\n0 10 0\n0 0 10\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

inline const std::filesystem::path& scene_assets() {
    static const std::filesystem::path folder = [] {
        const auto path = scratch_folder() / "scene";
        std::filesystem::create_directories(path);
        const std::string obj = kObj, ply = kPly;
        write_bytes(path / "figure.obj", reinterpret_cast<const std::uint8_t*>(obj.data()), obj.size());
        write_bytes(path / "figure.ply", reinterpret_cast<const std::uint8_t*>(ply.data()), ply.size());
        Image texture(4, 4, 3);
        for (int y = 0; y < 4; ++y)
            for (int x = 0; x < 4; ++x)
                for (int c = 0; c < 3; ++c) texture.at(x, y, c) = static_cast<float>((x + y + c) % 2);
        write_image(path / "texture.png", texture);
        return path;
    }();
    return folder;
}

}  // namespace rfd::fuzz
