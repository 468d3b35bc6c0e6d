// Scene files (scenes/*.toml): parse_scene, the meshes and textures a scene names taken
// from a folder of tiny ones (fuzz/scene_assets.hpp).
#include "fuzz/fuzz.hpp"
#include "fuzz/scene_assets.hpp"
#include "relight/scene.hpp"

using namespace rfd;

RFD_FUZZ_TARGET(scene) { relight::parse_scene(fuzz::text(data, size), "fuzz.toml", fuzz::scene_assets()); }
