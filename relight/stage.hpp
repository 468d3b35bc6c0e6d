#pragma once
// The virtual light stage (thesis chapter 4, 5.4): a deterministic CPU ray tracer that
// renders a scene, seen from one fixed camera, under one distant light at a time, producing
// the images R_i of a reflectance field.
//
// Radiometry (the convention of relight/): the light from unit direction d with kernel K
// (relight/light_kernel.hpp, integral of K over the sphere = 1) is a blend of directional
// lights of total irradiance 1. A pixel's value is the radiance reaching the camera,
//     I = sum over camera paths of  W * ( integral f_r(v, w) (n.w) V(w) K(w) dw  at the
//                                          diffuse or glossy point the path ends on,
//                                         or K(w_out) + background  when it escapes ),
// W the path's throughput (mirror reflectance, Fresnel and Beer-Lambert factors, 1/spp), V
// the visibility toward w. So a white Lambertian surface facing a directional light
// (radius 0) reads 1/pi, and a mirror shows the kernel itself: a disc of radiance
// 1 / (solid angle) for a constant kernel, invisible for an ideal directional light.
//
// How (speed matters: dense fields have thousands of lights): the camera paths through
// mirrors and glass do not depend on the light, so the constructor traces them once and
// caches, per pixel, the diffuse/glossy points they end on (position, normals, albedo,
// throughput) and the directions they escape in. render() then only evaluates the BRDF,
// casts shadow rays toward deterministic, stratified samples of the kernel (scene's
// shadow_samples per camera sample, rotated per pixel: soft shadows under wide kernels turn
// into fine noise rather than banding), and looks up K for the escaped paths.
//
// Approximations, on purpose:
//  - direct light only: no diffuse or glossy interreflection; indirect light reaches the
//    camera only through chains of mirror and glass interactions (up to max_depth; Fresnel
//    splits are followed on both branches, branches below 1e-4 of a pixel are dropped);
//  - shadows of glass: a shadow ray crosses glass in a straight line, attenuated by
//    Beer-Lambert absorption along the chord and by the normal-incidence Fresnel
//    transmittance at each surface; no refraction of the light, hence no caustics;
//  - glass objects may nest (liquid in a bottle): the innermost one entered gives the
//    medium; their surfaces must not touch.
//
// Determinism: every random number is a hash of (seed, pixel, sample), every sum runs in a
// fixed order, and the Embree BVH is built single-threaded: the same scene, seed and light
// give bit-identical images, whatever the thread count.
//
// Example: LightStage stage(load_scene("scenes/bottle.toml"));
//          Image image = stage.render({0.0, 0.5, 0.866}, LightKernel::narrow());

#include <cstddef>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "relight/field.hpp"
#include "relight/light_kernel.hpp"
#include "relight/scene.hpp"

namespace rfd::relight {

/// A lamp at a finite distance, as a dome's: a sphere of `radius` mm at `position` (mm, the
/// first camera's field frame, about the world's origin), bright enough to give irradiance 1
/// at `reference_distance` mm. Surfaces see it as a point (each from its own direction, with
/// the inverse-square fall-off), mirrors as the sphere.
struct NearLamp {
    Eigen::Vector3d position = Eigen::Vector3d::UnitZ();
    double radius = 1.0;
    double reference_distance = 1.0;
};

class LightStage {
public:
    /// Traces the camera paths of view `view` of `scene` (shows progress on stderr).
    explicit LightStage(Scene scene, std::size_t view = 0);
    ~LightStage();
    LightStage(const LightStage&) = delete;
    LightStage& operator=(const LightStage&) = delete;

    const Scene& scene() const;
    std::size_t view() const { return view_; }
    int width() const;
    int height() const;

    /// The image under the light from `direction` (unit, toward the light, in the field
    /// frame of the scene's first camera) with `kernel`: linear RGB, radiance. Thread-safe;
    /// parallel over pixels inside.
    Image render(const Eigen::Vector3d& direction, const LightKernel& kernel) const;
    /// The same with the scene's kernel.
    Image render(const Eigen::Vector3d& direction) const;
    /// The image under a near lamp (hard shadows: the lamp is a point for surfaces).
    Image render(const NearLamp& lamp) const;

    /// Rotation from the first camera's field frame to this view's field frame: the
    /// direction this view's light file records for a light at `d` is to_view_frame() * d.
    Eigen::Matrix3d to_view_frame() const;

    /// Size of the light-independent cache.
    std::size_t shading_point_count() const;
    std::size_t escaped_path_count() const;

private:
    struct Cache;
    Image render_lit(const Eigen::Vector3d& direction, const LightKernel& kernel, const NearLamp* near) const;
    std::unique_ptr<const Scene> scene_;
    std::size_t view_ = 0;
    std::unique_ptr<Cache> cache_;
};

/// Renders one image per direction (field frame of the scene's first camera) into a field
/// for `stage`'s view: directions converted to the view's frame, kernel radii recorded
/// unless the kernel is directional. Progress on stderr. Holds every image in memory: for
/// thousands of lights, render and write one at a time instead (as `rfd capture render`).
ReflectanceField render_field(const LightStage& stage, const std::vector<Eigen::Vector3d>& directions,
                              const LightKernel& kernel);

}  // namespace rfd::relight
