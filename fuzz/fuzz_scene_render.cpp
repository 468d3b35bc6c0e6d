// Scene files, rendered: parse_scene, then what `rfd capture render` does with the scene,
// small: the light stage of the first camera at 4 x 3 pixels, one sample, under one light.
// Values the reader accepts must not break the ray tracer (Embree aborts on a ray through
// coordinates a float cannot hold).
#include <utility>

#include <Eigen/Core>

#include "core/progress.hpp"
#include "fuzz/fuzz.hpp"
#include "fuzz/scene_assets.hpp"
#include "relight/scene.hpp"
#include "relight/stage.hpp"

using namespace rfd;

RFD_FUZZ_TARGET(scene_render) {
    Progress::set_quiet(true);
    relight::Scene scene = relight::parse_scene(fuzz::text(data, size), "fuzz.toml", fuzz::scene_assets());
    for (relight::Camera& camera : scene.cameras) {
        camera.width = 4;
        camera.height = 3;
    }
    scene.samples_per_pixel = 1;
    scene.shadow_samples = 1;
    const relight::LightStage stage(std::move(scene));
    stage.render(Eigen::Vector3d(0.3, 0.2, 0.9).normalized());
}
