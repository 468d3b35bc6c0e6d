#pragma once
// A reflectance field rendered on the virtual light stage (relight/stage.hpp), one folder
// per camera of the scene, as `rfd capture render` writes it: what the stage rendered, and
// how long it took, for its report.
//
// Example:
//   const StageRender run = render_field(scene, directions, kernels, "out/bottle");
//   std::fputs(stage_render_text(run, scene, "scenes/bottle.toml", "out/bottle").c_str(), stdout);

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "relight/light_kernel.hpp"
#include "relight/scene.hpp"

namespace rfd::relight {

struct StageRender {
    std::size_t views = 0, lights = 0;
    std::size_t shading_points = 0, escaped_paths = 0;  ///< over every view's cache
    double camera_seconds = 0.0;     ///< tracing the camera paths (the cache)
    double seconds_per_light = 0.0;  ///< lighting them, per light and view
    LightKernel kernel;              ///< the command's kernel, for the report
    std::string light_source;        ///< where the directions came from (a count, a file)
    double dome_radius_mm = 0.0;     ///< lamps at this distance from the origin (0: distant)
};

/// Renders `directions[i]` (unit, toward the light, the first camera's field frame) with
/// `kernels[i]` into `folder` (one camera) or folder/view_NN/ with views.txt (several, the
/// views in the display frame: the first camera's field frame). A views.txt of an earlier
/// run is removed first and written last.
/// With `dome_radius_mm` > 0 the lamps are near, as a dome's: each at that distance from the
/// world's origin along its direction, of the radius its kernel subtends from there
/// (relight/stage.hpp NearLamp); the light file records the directions from the origin.
StageRender render_field(const Scene& scene, const std::vector<Eigen::Vector3d>& directions,
                         const std::vector<LightKernel>& kernels, const std::filesystem::path& folder,
                         double dome_radius_mm = 0.0);

/// The run for --json and as text; `scene_file` and `folder` as the user named them.
nlohmann::json stage_render_json(const StageRender& run, const Scene& scene, const std::string& scene_file,
                                 const std::string& folder);
std::string stage_render_text(const StageRender& run, const Scene& scene, const std::string& scene_file,
                              const std::string& folder);

}  // namespace rfd::relight
