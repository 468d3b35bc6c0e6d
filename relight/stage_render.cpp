#include "relight/stage_render.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <system_error>

#include "core/error.hpp"
#include "core/files.hpp"
#include "core/progress.hpp"
#include "core/text.hpp"
#include "core/units.hpp"
#include "relight/field.hpp"
#include "relight/stage.hpp"
#include "relight/view_set.hpp"

namespace rfd::relight {

StageRender render_field(const Scene& scene, const std::vector<Eigen::Vector3d>& directions,
                         const std::vector<LightKernel>& kernels, const std::filesystem::path& folder,
                         double dome_radius_mm) {
    using Clock = std::chrono::steady_clock;
    RFD_CHECK(directions.size() == kernels.size());
    ensure_directory(folder);
    StageRender run;
    run.views = scene.cameras.size();
    run.lights = directions.size();
    run.dome_radius_mm = dome_radius_mm;
    double light_seconds = 0.0;
    std::vector<ViewEntry> view_entries;
    // A views file from an earlier run would list views being replaced: written last.
    std::error_code stale;
    std::filesystem::remove(folder / "views.txt", stale);
    for (std::size_t v = 0; v < run.views; ++v) {
        char name[32];
        std::snprintf(name, sizeof name, "view_%02zu", v);
        FieldWriter field(run.views == 1 ? folder : folder / name);

        const auto t0 = Clock::now();
        const LightStage stage(scene, v);
        const auto t1 = Clock::now();
        run.camera_seconds += std::chrono::duration<double>(t1 - t0).count();
        run.shading_points += stage.shading_point_count();
        run.escaped_paths += stage.escaped_path_count();

        Progress progress(run.views == 1 ? "lights" : std::string("lights, ") + name, directions.size());
        for (std::size_t i = 0; i < directions.size(); ++i) {
            // A dome's lamp subtends its kernel's radius from the origin (a tenth of a degree at least).
            const double lamp_radius = dome_radius_mm * std::tan(std::max(kernels[i].radius, degrees_to_radians(0.1)));
            field.add(dome_radius_mm > 0.0
                          ? stage.render(NearLamp{dome_radius_mm * directions[i].normalized(), lamp_radius, dome_radius_mm})
                          : stage.render(directions[i], kernels[i]),
                      (stage.to_view_frame() * directions[i]).normalized(), kernels[i].radius);
            progress.advance();
        }
        progress.finish();
        light_seconds += std::chrono::duration<double>(Clock::now() - t1).count();
        field.finish();
        // The view in the display frame (the first camera's field frame): the direction
        // toward this camera from what it looks at, and the rotation back from its
        // light frame.
        const Camera& cam = scene.cameras[v];
        const Eigen::Vector3d toward =
            scene.cameras.front().field_frame().transpose() * (cam.position - cam.look_at).normalized();
        view_entries.push_back({name, toward, stage.to_view_frame().transpose(), 0});
    }
    if (run.views > 1) write_view_file(folder / "views.txt", view_entries);
    run.seconds_per_light = light_seconds / static_cast<double>(run.views * directions.size());
    return run;
}

nlohmann::json stage_render_json(const StageRender& run, const Scene& scene, const std::string& scene_file,
                                 const std::string& folder) {
    const Camera& camera = scene.cameras.front();
    return {{"scene", scene_file},
            {"out", folder},
            {"views", run.views},
            {"lights", run.lights},
            {"light_source", run.light_source},
            {"resolution", {camera.width, camera.height}},
            {"samples_per_pixel", scene.samples_per_pixel},
            {"shadow_samples", scene.shadow_samples},
            {"seed", scene.seed},
            {"dome_radius_mm", run.dome_radius_mm},
            {"kernel", {{"profile", to_string(run.kernel.profile)},
                        {"radius_deg", radians_to_degrees(run.kernel.radius)},
                        {"directional", run.kernel.is_directional()}}},
            {"shading_points", run.shading_points},
            {"escaped_paths", run.escaped_paths},
            {"camera_paths_seconds", run.camera_seconds},
            {"seconds_per_light", run.seconds_per_light}};
}

std::string stage_render_text(const StageRender& run, const Scene& scene, const std::string& scene_file,
                              const std::string& folder) {
    const Camera& camera = scene.cameras.front();
    std::string text;
    text += format_text("rendered %zu light(s) x %zu view(s) of %s into %s\n", run.lights, run.views,
                  scene_file.c_str(), folder.c_str());
    text += format_text("  image              %d x %d, %d camera ray(s) per pixel\n", camera.width,
                  camera.height, scene.samples_per_pixel);
    text += format_text("  kernel             %s, radius %.3g deg, %d shadow sample(s) per ray\n",
                  run.kernel.is_directional() ? "directional" : to_string(run.kernel.profile).c_str(),
                  radians_to_degrees(run.kernel.radius), scene.shadow_samples);
    if (run.dome_radius_mm > 0.0)
        text += format_text("  lamps              near: %.4g mm from the origin (a dome), hard shadows\n",
                            run.dome_radius_mm);
    text += format_text("  cache              %zu shading points, %zu escaped paths\n", run.shading_points,
                  run.escaped_paths);
    text += format_text("  time               %.3f s camera paths, %.4f s per light\n",
                  run.camera_seconds, run.seconds_per_light);
    return text;
}

}  // namespace rfd::relight
