#include "relight/stage.hpp"

#include <array>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/units.hpp"
#include "relight/brdf.hpp"
#include "relight/ray_scene.hpp"

namespace rfd::relight {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kGoldenFraction = 0.6180339887498949;  // 1 / golden ratio
// Camera-path branches carrying less than this fraction of a pixel are dropped.
constexpr double kPruneWeight = 1e-4;
// Glass surfaces a shadow ray may cross before it is deemed blocked.
constexpr int kMaxGlassCrossings = 32;
constexpr int kMaxNesting = 8;

// SplitMix64 (Steele et al. 2014): a stateless hash of (seed, pixel, stream).
std::uint64_t mix(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

double unit_from_hash(std::uint64_t h) { return static_cast<double>(h >> 11) * 0x1.0p-53; }

// Two uniform numbers for pixel p and one stream: the per-pixel rotation of a lattice.
std::array<double, 2> pixel_offset(std::uint64_t seed, std::size_t pixel, std::uint64_t stream) {
    const std::uint64_t h = mix(mix(seed ^ (stream * 0xD1B54A32D192ED03ull)) ^ pixel);
    return {unit_from_hash(h), unit_from_hash(mix(h))};
}

double wrap(double x) { return x - std::floor(x); }

// Point i of an n-point Fibonacci lattice in [0, 1)^2: stratified for any n.
std::array<double, 2> lattice(std::size_t i, std::size_t n) {
    return {(static_cast<double>(i) + 0.5) / static_cast<double>(n),
            wrap(static_cast<double>(i) * kGoldenFraction)};
}

struct ShadingPoint {
    Eigen::Vector3f origin;          // surface point lifted off the surface toward the viewer
    Eigen::Vector3f normal;          // shading normal, facing the viewer's side
    Eigen::Vector3f geometric;       // geometric normal, same side
    Eigen::Vector3f view;            // toward the viewer (previous path vertex)
    Eigen::Array3f weight;           // path throughput, 1/spp included
    Eigen::Array3f albedo;           // texture looked up
    std::uint32_t material = 0;
    std::uint32_t sample = 0;        // camera sample index within the pixel
};

struct EscapedPath {
    Eigen::Vector3f origin;     // world, the path's last vertex
    Eigen::Vector3f direction;  // world
    Eigen::Array3f weight;
};

// One image row of the cache; pixel x owns points [point_begin[x], point_begin[x + 1]).
struct RowCache {
    std::vector<ShadingPoint> points;
    std::vector<EscapedPath> escapes;
    std::vector<std::uint32_t> point_begin;
    std::vector<std::uint32_t> escape_begin;
    std::vector<Eigen::Array3f> background;  // per pixel: background * escaped throughput
};

struct Media {
    std::array<std::uint32_t, kMaxNesting> objects{};
    int count = 0;

    bool empty() const { return count == 0; }
    std::uint32_t top() const { return objects[static_cast<std::size_t>(count - 1)]; }
    bool contains(std::uint32_t object) const {
        for (int i = 0; i < count; ++i)
            if (objects[static_cast<std::size_t>(i)] == object) return true;
        return false;
    }
    void push(std::uint32_t object) {
        if (count < kMaxNesting) objects[static_cast<std::size_t>(count++)] = object;
    }
    void remove(std::uint32_t object) {
        for (int i = count - 1; i >= 0; --i) {
            if (objects[static_cast<std::size_t>(i)] != object) continue;
            for (int j = i; j + 1 < count; ++j)
                objects[static_cast<std::size_t>(j)] = objects[static_cast<std::size_t>(j + 1)];
            --count;
            return;
        }
    }
};

struct PathState {
    Eigen::Vector3d origin;
    Eigen::Vector3d direction;
    Rgb weight;
    int depth = 0;
    Media media;
};

const GlassMaterial& glass_of(const Scene& scene, std::uint32_t object) {
    return std::get<GlassMaterial>(scene.materials[scene.objects[object].material]);
}

double ior_of(const Scene& scene, const Media& media) {
    return media.empty() ? 1.0 : glass_of(scene, media.top()).ior;
}

Rgb beer_lambert(const Rgb& absorption, double distance) { return (-absorption * distance).exp(); }

}  // namespace

struct LightStage::Cache {
    Cache(const Scene& scene)
        : all(scene, ObjectFilter::All), opaque(scene, ObjectFilter::Opaque),
          glass(scene, ObjectFilter::Glass) {}
    RayScene all, opaque, glass;
    std::vector<RowCache> rows;
    Eigen::Matrix3d field_to_world;   // first camera's field frame
    Eigen::Matrix3d to_view_frame;
};

namespace {

class CameraTracer {
public:
    CameraTracer(const Scene& scene, const RayScene& rays) : scene_(scene), rays_(rays) {}

    void trace(PathState start, std::uint32_t sample, RowCache& row) const {
        std::vector<PathState> pending{std::move(start)};
        const double prune = kPruneWeight / scene_.samples_per_pixel;
        const double eps = rays_.epsilon();
        while (!pending.empty()) {
            PathState path = std::move(pending.back());
            pending.pop_back();
            if (path.weight.maxCoeff() < prune) continue;
            const auto hit = rays_.intersect(path.origin, path.direction, 0.0, kInfinity);
            if (!hit) {
                EscapedPath escaped;
                escaped.origin = path.origin.cast<float>();
                escaped.direction = path.direction.cast<float>();
                escaped.weight = path.weight.cast<float>();
                row.escapes.push_back(escaped);
                row.background.back() += (path.weight * scene_.background).cast<float>();
                continue;
            }
            if (!path.media.empty())
                path.weight *= beer_lambert(glass_of(scene_, path.media.top()).absorption, hit->t);
            const Eigen::Vector3d p = path.origin + hit->t * path.direction;
            const Eigen::Vector3d view = -path.direction;
            const Material& material = scene_.materials[scene_.objects[hit->object].material];

            if (const auto* glass = std::get_if<GlassMaterial>(&material)) {
                if (path.depth >= scene_.max_depth) continue;
                refract(path, *hit, p, *glass, pending, eps);
                continue;
            }
            // Opaque: orient both normals toward the side the path arrives from.
            Eigen::Vector3d geometric = hit->normal, shading = hit->shading_normal;
            if (geometric.dot(view) < 0.0) {
                geometric = -geometric;
                shading = -shading;
            }
            if (const auto* mirror = std::get_if<MirrorMaterial>(&material)) {
                if (path.depth >= scene_.max_depth) continue;
                Eigen::Vector3d reflected = path.direction - 2.0 * path.direction.dot(shading) * shading;
                if (reflected.dot(geometric) <= 0.0)  // interpolated normal tilted too far
                    reflected = path.direction - 2.0 * path.direction.dot(geometric) * geometric;
                PathState next = path;
                next.origin = p + eps * geometric;
                next.direction = reflected.normalized();
                next.weight = path.weight * mirror->reflectance;
                ++next.depth;
                pending.push_back(std::move(next));
                continue;
            }
            ShadingPoint point;
            point.origin = (p + eps * geometric).cast<float>();
            point.normal = shading.cast<float>();
            point.geometric = geometric.cast<float>();
            point.view = view.cast<float>();
            point.weight = path.weight.cast<float>();
            point.albedo = albedo_at(*albedo_of(material), p, hit->normal, hit->uv).cast<float>();
            point.material = static_cast<std::uint32_t>(scene_.objects[hit->object].material);
            point.sample = sample;
            row.points.push_back(point);
        }
    }

private:
    // Fresnel split at a glass surface: both the reflected and the refracted branch go on.
    void refract(const PathState& path, const RayHit& hit, const Eigen::Vector3d& p,
                 const GlassMaterial& glass, std::vector<PathState>& pending, double eps) const {
        const bool entering = path.direction.dot(hit.normal) < 0.0;
        Media after = path.media;
        if (entering) {
            after.push(hit.object);
        } else if (after.contains(hit.object)) {
            after.remove(hit.object);
        }
        const double n1 = entering ? ior_of(scene_, path.media) : glass.ior;
        const double n2 = entering ? glass.ior : ior_of(scene_, after);
        // Normals on the side the path arrives from.
        Eigen::Vector3d facing = entering ? hit.shading_normal : Eigen::Vector3d(-hit.shading_normal);
        const Eigen::Vector3d facing_geometric = entering ? hit.normal : Eigen::Vector3d(-hit.normal);
        if (facing.dot(-path.direction) <= 0.0) facing = facing_geometric;
        const double cos_i = std::min(1.0, -path.direction.dot(facing));
        const double reflectance = fresnel_dielectric(cos_i, n1, n2);

        PathState reflected = path;
        reflected.origin = p + eps * facing_geometric;
        reflected.direction = (path.direction + 2.0 * cos_i * facing).normalized();
        reflected.weight = path.weight * reflectance;
        reflected.depth = path.depth + 1;
        if (reflected.direction.dot(facing_geometric) > 0.0) pending.push_back(reflected);

        if (reflectance >= 1.0) return;  // total internal reflection
        const double eta = n1 / n2;
        const double cos_t = std::sqrt(std::max(0.0, 1.0 - eta * eta * (1.0 - cos_i * cos_i)));
        PathState refracted = path;
        refracted.origin = p - eps * facing_geometric;
        refracted.direction = (eta * path.direction + (eta * cos_i - cos_t) * facing).normalized();
        refracted.weight = path.weight * (1.0 - reflectance);
        refracted.depth = path.depth + 1;
        refracted.media = after;
        if (refracted.direction.dot(facing_geometric) < 0.0) pending.push_back(refracted);
    }

    const Scene& scene_;
    const RayScene& rays_;
};

}  // namespace

LightStage::LightStage(Scene scene, std::size_t view)
    : scene_(std::make_unique<const Scene>(std::move(scene))), view_(view) {
    const Scene& s = *scene_;
    RFD_CHECK(view_ < s.cameras.size());
    RFD_CHECK(s.samples_per_pixel >= 1 && s.shadow_samples >= 1);
    cache_ = std::make_unique<Cache>(s);
    const Camera& camera = s.cameras[view_];
    cache_->field_to_world = s.cameras.front().field_frame();
    cache_->to_view_frame = camera.field_frame().transpose() * cache_->field_to_world;
    cache_->rows.resize(static_cast<std::size_t>(camera.height));
    const CameraTracer tracer(s, cache_->all);
    const auto spp = static_cast<std::size_t>(s.samples_per_pixel);
    Progress progress("camera paths", static_cast<std::size_t>(camera.height));
    parallel_for_chunks(static_cast<std::size_t>(camera.height), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t y = begin; y < end; ++y) {
            RowCache& row = cache_->rows[y];
            for (int x = 0; x < camera.width; ++x) {
                row.point_begin.push_back(static_cast<std::uint32_t>(row.points.size()));
                row.escape_begin.push_back(static_cast<std::uint32_t>(row.escapes.size()));
                row.background.push_back(Eigen::Array3f::Zero());
                const std::size_t pixel = y * static_cast<std::size_t>(camera.width) + static_cast<std::size_t>(x);
                const auto offset = pixel_offset(s.seed, pixel, 1);
                for (std::size_t k = 0; k < spp; ++k) {
                    // One sample: the pixel centre; more: a rotated Fibonacci lattice.
                    std::array<double, 2> at{0.5, 0.5};
                    if (spp > 1) {
                        const auto l = lattice(k, spp);
                        at = {wrap(l[0] + offset[0]), wrap(l[1] + offset[1])};
                    }
                    PathState path;
                    path.origin = camera.position;
                    path.direction = camera.ray_direction(x + at[0], static_cast<double>(y) + at[1]);
                    path.weight = Rgb::Constant(1.0 / static_cast<double>(spp));
                    tracer.trace(path, static_cast<std::uint32_t>(k), row);
                }
            }
            row.point_begin.push_back(static_cast<std::uint32_t>(row.points.size()));
            row.escape_begin.push_back(static_cast<std::uint32_t>(row.escapes.size()));
            progress.advance();
        }
    });
    progress.finish();
}

LightStage::~LightStage() = default;

const Scene& LightStage::scene() const { return *scene_; }
int LightStage::width() const { return scene_->cameras[view_].width; }
int LightStage::height() const { return scene_->cameras[view_].height; }
Eigen::Matrix3d LightStage::to_view_frame() const { return cache_->to_view_frame; }

std::size_t LightStage::shading_point_count() const {
    std::size_t count = 0;
    for (const auto& row : cache_->rows) count += row.points.size();
    return count;
}

std::size_t LightStage::escaped_path_count() const {
    std::size_t count = 0;
    for (const auto& row : cache_->rows) count += row.escapes.size();
    return count;
}

Image LightStage::render(const Eigen::Vector3d& direction) const {
    return render(direction, scene_->kernel);
}

Image LightStage::render(const Eigen::Vector3d& direction, const LightKernel& kernel) const {
    return render_lit(direction, kernel, nullptr);
}

Image LightStage::render(const NearLamp& lamp) const {
    RFD_CHECK(lamp.radius > 0.0 && lamp.reference_distance > 0.0);
    return render_lit(lamp.position.normalized(), LightKernel::directional(), &lamp);
}

Image LightStage::render_lit(const Eigen::Vector3d& direction, const LightKernel& kernel, const NearLamp* near) const {
    const Scene& s = *scene_;
    const Cache& cache = *cache_;
    const KernelSampler sampler(kernel);
    const Eigen::Vector3d centre = (cache.field_to_world * direction.normalized()).normalized();
    // A near lamp: a point for the surfaces (its direction, distance and inverse-square
    // fall-off from each), a sphere of its radius for mirrors, of the radiance that gives
    // irradiance 1 at the reference distance.
    const Eigen::Vector3d lamp = near ? Eigen::Vector3d(cache.field_to_world * near->position) : Eigen::Vector3d::Zero();
    const double lamp_radiance =
        near ? near->reference_distance * near->reference_distance / (kPi * near->radius * near->radius) : 0.0;
    const bool directional = kernel.is_directional();
    const std::size_t per_sample = directional ? 1 : static_cast<std::size_t>(s.shadow_samples);
    const std::size_t strata = per_sample * static_cast<std::size_t>(s.samples_per_pixel);
    const double eps = cache.all.epsilon();
    const int width = this->width();
    Image image(width, height(), 3);

    // Visibility toward w from a shading point: 0 behind an opaque object, attenuated
    // (straight chords, no refraction) through glass.
    auto transmittance = [&](const Eigen::Vector3d& origin, const Eigen::Vector3d& w, double reach) -> Rgb {
        if (cache.opaque.occluded(origin, w, 0.0, reach)) return Rgb::Zero();
        Rgb through = Rgb::Ones();
        if (cache.glass.empty()) return through;
        Media media;
        double t = 0.0;
        for (int crossing = 0; crossing < kMaxGlassCrossings; ++crossing) {
            const auto hit = cache.glass.intersect(origin, w, t + eps, reach);
            if (!hit) return through;
            const bool entering = w.dot(hit->normal) < 0.0;
            // A surface left without having been entered: the point sits inside it.
            const std::uint32_t medium = !media.empty() ? media.top()
                                         : (!entering ? hit->object : std::numeric_limits<std::uint32_t>::max());
            if (medium != std::numeric_limits<std::uint32_t>::max())
                through *= beer_lambert(glass_of(s, medium).absorption, hit->t - t);
            const double n1 = entering ? ior_of(s, media) : glass_of(s, hit->object).ior;
            Media after = media;
            if (entering) after.push(hit->object);
            else after.remove(hit->object);
            const double n2 = entering ? glass_of(s, hit->object).ior : ior_of(s, after);
            const double r0 = (n1 - n2) / (n1 + n2);
            through *= 1.0 - r0 * r0;
            media = after;
            t = hit->t;
        }
        return Rgb::Zero();
    };

    parallel_for_chunks(static_cast<std::size_t>(height()), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t y = begin; y < end; ++y) {
            const RowCache& row = cache.rows[y];
            for (int x = 0; x < width; ++x) {
                const auto ux = static_cast<std::size_t>(x);
                const std::size_t pixel = y * static_cast<std::size_t>(width) + ux;
                Rgb sum = row.background[ux].cast<double>();
                if (near) {
                    // Escaped paths that pass within the lamp's radius of its centre see it.
                    for (std::uint32_t e = row.escape_begin[ux]; e < row.escape_begin[ux + 1]; ++e) {
                        const EscapedPath& escaped = row.escapes[e];
                        const Eigen::Vector3d o = escaped.origin.cast<double>();
                        const Eigen::Vector3d d = escaped.direction.cast<double>().normalized();
                        const double along = std::max(0.0, (lamp - o).dot(d));
                        if ((o + along * d - lamp).norm() < near->radius)
                            sum += escaped.weight.cast<double>() * lamp_radiance;
                    }
                } else if (!directional) {
                    for (std::uint32_t e = row.escape_begin[ux]; e < row.escape_begin[ux + 1]; ++e) {
                        const EscapedPath& escaped = row.escapes[e];
                        sum += escaped.weight.cast<double>() *
                               sampler.radiance(escaped.direction.cast<double>().normalized(), centre);
                    }
                }
                const auto offset = pixel_offset(s.seed, pixel, 2);
                for (std::uint32_t i = row.point_begin[ux]; i < row.point_begin[ux + 1]; ++i) {
                    const ShadingPoint& point = row.points[i];
                    const Eigen::Vector3d n = point.normal.cast<double>();
                    const Eigen::Vector3d ng = point.geometric.cast<double>();
                    const Eigen::Vector3d v = point.view.cast<double>();
                    const Eigen::Vector3d origin = point.origin.cast<double>();
                    const Rgb albedo = point.albedo.cast<double>();
                    const Material& material = s.materials[point.material];
                    Rgb reflected = Rgb::Zero();
                    if (near) {
                        const Eigen::Vector3d to_lamp = lamp - origin;
                        const double distance = to_lamp.norm();
                        const Eigen::Vector3d w = to_lamp / distance;
                        const double cosine = n.dot(w);
                        if (cosine > 0.0 && ng.dot(w) > 0.0) {
                            const double falloff = near->reference_distance * near->reference_distance / (distance * distance);
                            reflected = surface_brdf(material, n, v, w, albedo) * cosine * falloff *
                                        transmittance(origin, w, distance - near->radius);
                        }
                        sum += point.weight.cast<double>() * reflected;
                        continue;
                    }
                    for (std::size_t j = 0; j < per_sample; ++j) {
                        Eigen::Vector3d w = centre;
                        if (!directional) {
                            // Radial position from the golden-ratio coordinate, so that it is
                            // not tied to the sub-pixel position of the same camera sample.
                            const auto l = lattice(point.sample * per_sample + j, strata);
                            w = sampler.sample(centre, wrap(l[1] + offset[0]), wrap(l[0] + offset[1]));
                        }
                        const double cosine = n.dot(w);
                        if (cosine <= 0.0 || ng.dot(w) <= 0.0) continue;
                        const Rgb f = surface_brdf(material, n, v, w, albedo);
                        if (f.maxCoeff() <= 0.0) continue;
                        reflected += f * cosine * transmittance(origin, w, kInfinity);
                    }
                    sum += point.weight.cast<double>() * reflected / static_cast<double>(per_sample);
                }
                for (int c = 0; c < 3; ++c) image.at(x, static_cast<int>(y), c) = static_cast<float>(sum[c]);
            }
        }
    });
    return image;
}

ReflectanceField render_field(const LightStage& stage, const std::vector<Eigen::Vector3d>& directions,
                              const LightKernel& kernel) {
    ReflectanceField field;
    Progress progress("lights", directions.size());
    for (const Eigen::Vector3d& d : directions) {
        field.images.push_back(stage.render(d, kernel));
        field.directions.push_back((stage.to_view_frame() * d.normalized()).normalized());
        if (!kernel.is_directional()) field.kernel_radii.push_back(kernel.radius);
        progress.advance();
    }
    progress.finish();
    return field;
}

}  // namespace rfd::relight
