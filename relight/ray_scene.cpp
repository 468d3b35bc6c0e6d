#include "relight/ray_scene.hpp"

#include <cmath>
#include <limits>

#include <embree3/rtcore.h>

#include "core/error.hpp"

namespace rfd::relight {
namespace {

// Parts of a cylinder, reported in the hit's u so the normal can be rebuilt exactly.
constexpr float kCylinderSide = 0.0f;
constexpr float kCylinderBottom = 1.0f;
constexpr float kCylinderTop = 2.0f;

bool is_glass(const Scene& scene, const SceneObject& object) {
    return std::holds_alternative<GlassMaterial>(scene.materials[object.material]);
}

bool passes(const Scene& scene, const SceneObject& object, ObjectFilter filter) {
    switch (filter) {
        case ObjectFilter::All: return true;
        case ObjectFilter::Opaque: return !is_glass(scene, object);
        case ObjectFilter::Glass: return is_glass(scene, object);
    }
    return false;
}

// Nearest root of a sphere in (t_min, t_max); the normal is outward.
struct AnalyticHit {
    double t = 0.0;
    float part = 0.0f;
    Eigen::Vector3d normal;
};

std::optional<AnalyticHit> hit_sphere(const SphereShape& s, const Eigen::Vector3d& o,
                                      const Eigen::Vector3d& d, double t_min, double t_max) {
    // |o + t d - c|^2 = r^2 with the numerically stable half-b form.
    const Eigen::Vector3d oc = o - s.centre;
    const double a = d.squaredNorm();
    const double half_b = oc.dot(d);
    // c = |oc|^2 - r^2, computed as a difference of squares of the distance to the
    // closest approach to keep precision for far-away cameras.
    const Eigen::Vector3d closest = oc - (half_b / a) * d;
    const double disc = a * (s.radius * s.radius - closest.squaredNorm());
    if (disc < 0.0) return std::nullopt;
    const double root = std::sqrt(disc);
    const double q = -half_b - std::copysign(root, half_b);
    double t0 = q / a;
    double t1 = q != 0.0 ? (oc.squaredNorm() - s.radius * s.radius) / q : t0;
    if (t0 > t1) std::swap(t0, t1);
    for (const double t : {t0, t1})
        if (t > t_min && t < t_max) return AnalyticHit{t, 0.0f, (o + t * d - s.centre) / s.radius};
    return std::nullopt;
}

std::optional<AnalyticHit> hit_cylinder(const CylinderShape& c, const Eigen::Vector3d& o,
                                        const Eigen::Vector3d& d, double t_min, double t_max) {
    std::optional<AnalyticHit> best;
    auto consider = [&](double t, float part, const Eigen::Vector3d& normal) {
        if (t > t_min && t < t_max && (!best || t < best->t)) best = AnalyticHit{t, part, normal};
    };
    const Eigen::Vector3d oc = o - c.base;
    const double oa = oc.dot(c.axis), da = d.dot(c.axis);
    const Eigen::Vector3d op = oc - oa * c.axis, dp = d - da * c.axis;  // across the axis
    const double a = dp.squaredNorm();
    if (a > 1e-300) {
        const double half_b = op.dot(dp);
        const Eigen::Vector3d closest = op - (half_b / a) * dp;
        const double disc = a * (c.radius * c.radius - closest.squaredNorm());
        if (disc >= 0.0) {
            const double root = std::sqrt(disc);
            const double q = -half_b - std::copysign(root, half_b);
            const double roots[2] = {q / a, q != 0.0 ? (op.squaredNorm() - c.radius * c.radius) / q : q / a};
            for (const double t : roots) {
                const double h = oa + t * da;
                if (h >= 0.0 && h <= c.height) consider(t, kCylinderSide, (op + t * dp) / c.radius);
            }
        }
    }
    if (da != 0.0) {
        for (const auto& [height, part, sign] :
             {std::tuple{0.0, kCylinderBottom, -1.0}, std::tuple{c.height, kCylinderTop, 1.0}}) {
            const double t = (height - oa) / da;
            if ((op + t * dp).squaredNorm() <= c.radius * c.radius) consider(t, part, sign * c.axis);
        }
    }
    return best;
}

std::optional<AnalyticHit> hit_analytic(const SceneObject& object, const Eigen::Vector3d& o,
                                        const Eigen::Vector3d& d, double t_min, double t_max) {
    if (const auto* sphere = std::get_if<SphereShape>(&object.shape))
        return hit_sphere(*sphere, o, d, t_min, t_max);
    return hit_cylinder(std::get<CylinderShape>(object.shape), o, d, t_min, t_max);
}

struct UserData {
    const SceneObject* object = nullptr;
};

void analytic_bounds(const RTCBoundsFunctionArguments* args) {
    const auto* data = static_cast<const UserData*>(args->geometryUserPtr);
    Eigen::Vector3d lo, hi;
    if (const auto* s = std::get_if<SphereShape>(&data->object->shape)) {
        lo = s->centre.array() - s->radius;
        hi = s->centre.array() + s->radius;
    } else {
        const auto& c = std::get<CylinderShape>(data->object->shape);
        const Eigen::Vector3d top = c.base + c.height * c.axis;
        // A disc of radius r around unit axis a extends r * sqrt(1 - a_k^2) along axis k.
        const Eigen::Vector3d extent =
            c.radius * (Eigen::Vector3d::Ones() - c.axis.cwiseAbs2()).cwiseMax(0.0).cwiseSqrt();
        lo = c.base.cwiseMin(top) - extent;
        hi = c.base.cwiseMax(top) + extent;
    }
    // Widen by a float ulp or two so rounding never clips the surface.
    const double pad = 1e-6 * (1.0 + std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff()));
    args->bounds_o->lower_x = static_cast<float>(lo.x() - pad);
    args->bounds_o->lower_y = static_cast<float>(lo.y() - pad);
    args->bounds_o->lower_z = static_cast<float>(lo.z() - pad);
    args->bounds_o->upper_x = static_cast<float>(hi.x() + pad);
    args->bounds_o->upper_y = static_cast<float>(hi.y() + pad);
    args->bounds_o->upper_z = static_cast<float>(hi.z() + pad);
}

void analytic_intersect(const RTCIntersectFunctionNArguments* args) {
    const auto* data = static_cast<const UserData*>(args->geometryUserPtr);
    RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, args->N);
    RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, args->N);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const Eigen::Vector3d o(RTCRayN_org_x(ray, args->N, i), RTCRayN_org_y(ray, args->N, i),
                                RTCRayN_org_z(ray, args->N, i));
        const Eigen::Vector3d d(RTCRayN_dir_x(ray, args->N, i), RTCRayN_dir_y(ray, args->N, i),
                                RTCRayN_dir_z(ray, args->N, i));
        const auto found = hit_analytic(*data->object, o, d, RTCRayN_tnear(ray, args->N, i),
                                        RTCRayN_tfar(ray, args->N, i));
        if (!found) continue;
        RTCRayN_tfar(ray, args->N, i) = static_cast<float>(found->t);
        RTCHitN_Ng_x(hit, args->N, i) = static_cast<float>(found->normal.x());
        RTCHitN_Ng_y(hit, args->N, i) = static_cast<float>(found->normal.y());
        RTCHitN_Ng_z(hit, args->N, i) = static_cast<float>(found->normal.z());
        RTCHitN_u(hit, args->N, i) = found->part;
        RTCHitN_v(hit, args->N, i) = 0.0f;
        RTCHitN_primID(hit, args->N, i) = args->primID;
        RTCHitN_geomID(hit, args->N, i) = args->geomID;
        RTCHitN_instID(hit, args->N, i, 0) = args->context->instID[0];
    }
}

void analytic_occluded(const RTCOccludedFunctionNArguments* args) {
    const auto* data = static_cast<const UserData*>(args->geometryUserPtr);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const Eigen::Vector3d o(RTCRayN_org_x(args->ray, args->N, i), RTCRayN_org_y(args->ray, args->N, i),
                                RTCRayN_org_z(args->ray, args->N, i));
        const Eigen::Vector3d d(RTCRayN_dir_x(args->ray, args->N, i), RTCRayN_dir_y(args->ray, args->N, i),
                                RTCRayN_dir_z(args->ray, args->N, i));
        if (hit_analytic(*data->object, o, d, RTCRayN_tnear(args->ray, args->N, i),
                         RTCRayN_tfar(args->ray, args->N, i)))
            RTCRayN_tfar(args->ray, args->N, i) = -std::numeric_limits<float>::infinity();
    }
}

RTCRay make_ray(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min,
                double t_max) {
    RTCRay ray{};
    ray.org_x = static_cast<float>(origin.x());
    ray.org_y = static_cast<float>(origin.y());
    ray.org_z = static_cast<float>(origin.z());
    ray.dir_x = static_cast<float>(direction.x());
    ray.dir_y = static_cast<float>(direction.y());
    ray.dir_z = static_cast<float>(direction.z());
    ray.tnear = static_cast<float>(t_min);
    ray.tfar = t_max >= static_cast<double>(std::numeric_limits<float>::max())
                   ? std::numeric_limits<float>::infinity()
                   : static_cast<float>(t_max);
    ray.mask = 0xFFFFFFFFu;
    ray.flags = 0;
    ray.time = 0.0f;
    return ray;
}

}  // namespace

struct RayScene::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    std::vector<UserData> user_data;  // one per object, addresses stable after construction
    bool empty = true;

    ~Impl() {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }
};

double ray_epsilon(const Scene& scene) {
    double extent = 1.0;
    for (const Camera& camera : scene.cameras) extent = std::max(extent, camera.position.cwiseAbs().maxCoeff());
    for (const SceneObject& object : scene.objects) {
        if (const auto* s = std::get_if<SphereShape>(&object.shape))
            extent = std::max(extent, s->centre.cwiseAbs().maxCoeff() + s->radius);
        else if (const auto* c = std::get_if<CylinderShape>(&object.shape))
            extent = std::max(extent, c->base.cwiseAbs().maxCoeff() + c->height + c->radius);
        else
            for (const auto& p : std::get<MeshShape>(object.shape).positions)
                extent = std::max(extent, static_cast<double>(p.cwiseAbs().maxCoeff()));
    }
    // A float carries 24 bits: 2^-24 * extent is one ulp; 32 ulps clear Embree's own error.
    return std::max(1e-6, extent * 32.0 * std::ldexp(1.0, -24));
}

RayScene::RayScene(const Scene& scene, ObjectFilter filter)
    : impl_(std::make_unique<Impl>()), scene_(scene), epsilon_(ray_epsilon(scene)) {
    // Single-threaded builds keep the BVH identical run to run; scenes here are small
    // enough that the build takes milliseconds.
    impl_->device = rtcNewDevice("threads=1");
    RFD_CHECK_MSG(impl_->device != nullptr, "Embree device creation failed");
    impl_->scene = rtcNewScene(impl_->device);
    rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);
    impl_->user_data.resize(scene.objects.size());
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        const SceneObject& object = scene.objects[i];
        if (!passes(scene, object, filter)) continue;
        RTCGeometry geometry = nullptr;
        if (const auto* mesh = std::get_if<MeshShape>(&object.shape)) {
            geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
            auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
                geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                mesh->positions.size()));
            for (std::size_t v = 0; v < mesh->positions.size(); ++v)
                for (int k = 0; k < 3; ++k) vertices[3 * v + k] = mesh->positions[v][k];
            auto* indices = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(
                geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(std::uint32_t),
                mesh->triangles.size()));
            for (std::size_t t = 0; t < mesh->triangles.size(); ++t)
                for (int k = 0; k < 3; ++k) indices[3 * t + k] = mesh->triangles[t][k];
        } else {
            impl_->user_data[i].object = &object;
            geometry = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_USER);
            rtcSetGeometryUserPrimitiveCount(geometry, 1);
            rtcSetGeometryUserData(geometry, &impl_->user_data[i]);
            rtcSetGeometryBoundsFunction(geometry, analytic_bounds, nullptr);
            rtcSetGeometryIntersectFunction(geometry, analytic_intersect);
            rtcSetGeometryOccludedFunction(geometry, analytic_occluded);
        }
        rtcCommitGeometry(geometry);
        rtcAttachGeometryByID(impl_->scene, geometry, static_cast<unsigned>(i));
        rtcReleaseGeometry(geometry);
        impl_->empty = false;
    }
    rtcCommitScene(impl_->scene);
    RFD_CHECK_MSG(rtcGetDeviceError(impl_->device) == RTC_ERROR_NONE, "Embree scene build failed");
}

RayScene::~RayScene() = default;

bool RayScene::empty() const { return impl_->empty; }

std::optional<RayHit> RayScene::intersect(const Eigen::Vector3d& origin,
                                          const Eigen::Vector3d& direction, double t_min,
                                          double t_max) const {
    if (impl_->empty) return std::nullopt;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rayhit{};
    rayhit.ray = make_ray(origin, direction, t_min, t_max);
    rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &context, &rayhit);
    if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;

    RayHit hit;
    hit.t = rayhit.ray.tfar;
    hit.object = rayhit.hit.geomID;
    const SceneObject& object = scene_.objects[hit.object];
    if (const auto* mesh = std::get_if<MeshShape>(&object.shape)) {
        const auto& tri = mesh->triangles[rayhit.hit.primID];
        const Eigen::Vector3d p0 = mesh->positions[tri[0]].cast<double>();
        const Eigen::Vector3d p1 = mesh->positions[tri[1]].cast<double>();
        const Eigen::Vector3d p2 = mesh->positions[tri[2]].cast<double>();
        hit.normal = (p1 - p0).cross(p2 - p0).normalized();
        const double u = rayhit.hit.u, v = rayhit.hit.v, w = 1.0 - u - v;
        hit.shading_normal = hit.normal;
        if (!mesh->normals.empty()) {
            const Eigen::Vector3d n = w * mesh->normals[tri[0]].cast<double>() +
                                      u * mesh->normals[tri[1]].cast<double>() +
                                      v * mesh->normals[tri[2]].cast<double>();
            if (n.norm() > 1e-12) hit.shading_normal = n.normalized();
        }
        if (!mesh->uvs.empty())
            hit.uv = (w * mesh->uvs[tri[0]] + u * mesh->uvs[tri[1]] + v * mesh->uvs[tri[2]]).cast<double>();
    } else {
        // Rebuild the exact normal in double precision from the analytic shape.
        const Eigen::Vector3d p = origin + hit.t * direction;
        if (const auto* s = std::get_if<SphereShape>(&object.shape)) {
            hit.normal = (p - s->centre).normalized();
        } else {
            const auto& c = std::get<CylinderShape>(object.shape);
            if (rayhit.hit.u == kCylinderBottom) {
                hit.normal = -c.axis;
            } else if (rayhit.hit.u == kCylinderTop) {
                hit.normal = c.axis;
            } else {
                const Eigen::Vector3d r = p - c.base;
                hit.normal = (r - r.dot(c.axis) * c.axis).normalized();
            }
        }
        hit.shading_normal = hit.normal;
    }
    return hit;
}

bool RayScene::occluded(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                        double t_min, double t_max) const {
    if (impl_->empty) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray = make_ray(origin, direction, t_min, t_max);
    rtcOccluded1(impl_->scene, &context, &ray);
    return ray.tfar < 0.0f;
}

}  // namespace rfd::relight
