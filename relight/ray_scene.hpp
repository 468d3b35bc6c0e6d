#pragma once
// Ray queries against a scene's objects, on Embree 3 (Intel's CPU ray tracing kernels).
//
// Triangle meshes (meshes, boxes, cards, planes) are Embree triangle geometry; spheres and
// capped cylinders are Embree user geometry with analytic, double-precision intersection, so
// their normals are exact (the closed-form tests of the light stage depend on it). Embree
// works in single precision: callers offset ray origins by a small distance (epsilon()) to
// leave the surface they start on.
// Frame: the scene's world frame, millimetres; directions unit length.
//
// Example: RayScene rays(scene, ObjectFilter::All);
//          if (auto hit = rays.intersect(origin, direction, 0.0, kInfinity)) hit->object;

#include <cstdint>
#include <memory>
#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "relight/scene.hpp"

namespace rfd::relight {

/// What a ray hit.
struct RayHit {
    double t = 0.0;                 ///< distance along the (unit) direction, mm
    std::uint32_t object = 0;       ///< index into Scene::objects
    Eigen::Vector3d normal;         ///< geometric, unit; outward for closed solids (meshes: winding)
    Eigen::Vector3d shading_normal; ///< interpolated vertex normal, or `normal`
    Eigen::Vector2d uv = Eigen::Vector2d::Zero();  ///< texture coordinates (meshes with uvs)
};

/// Which objects a RayScene holds, by their material.
enum class ObjectFilter {
    All,     ///< everything (camera paths)
    Opaque,  ///< diffuse, glossy and mirror objects (shadow rays)
    Glass,   ///< glass objects only (attenuation of shadow rays)
};

class RayScene {
public:
    RayScene(const Scene& scene, ObjectFilter filter);
    ~RayScene();
    RayScene(const RayScene&) = delete;
    RayScene& operator=(const RayScene&) = delete;

    /// True when no object passed the filter (every query misses).
    bool empty() const;
    /// Nearest hit with t in (t_min, t_max), or nothing. Thread-safe.
    std::optional<RayHit> intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                    double t_min, double t_max) const;
    /// Whether anything lies along the ray with t in (t_min, t_max). Thread-safe.
    bool occluded(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min,
                  double t_max) const;
    /// A distance that safely separates a new ray's origin from the surface it leaves:
    /// a few float ulps of the scene's extent.
    double epsilon() const { return epsilon_; }

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    const Scene& scene_;
    double epsilon_ = 1e-3;
};

/// Offset from the scene's bounding box: the largest absolute coordinate of any object
/// or camera, times a few float ulps; at least 1e-6 mm.
double ray_epsilon(const Scene& scene);

}  // namespace rfd::relight
