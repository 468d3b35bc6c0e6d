#pragma once
// A virtual light-stage scene: camera(s), objects, materials, the light kernel (thesis 4.2,
// 5.4), read from TOML (format in docs/formats.md, "Scene files").
//
// World frame: right-handed, millimetres, as the scene file writes it. The field frame of
// light directions (core/sphere.hpp) is the first camera's: x right and y up in its image,
// z toward it. The bundled scenes put the table in the plane z = 0. spheres.toml looks
// straight down -z with +y up, so its world and field frames coincide and the light
// hemisphere z > 0 is the one above the table; bottle.toml and figure.toml look from the
// front and above, so their field frame is the world frame tilted about x.
//
// Example: Scene scene = load_scene("scenes/bottle.toml"); scene.cameras[0].width;

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/image.hpp"
#include "relight/brdf.hpp"
#include "relight/light_kernel.hpp"
#include "relight/mesh.hpp"

namespace rfd::relight {

/// A pinhole camera. Pixel (px, py) are continuous image coordinates: (0, 0) the top-left
/// corner of the image, x right, y down, one unit per pixel; pixel centres at +0.5.
struct Camera {
    Eigen::Vector3d position = Eigen::Vector3d(0, 0, 500);  ///< mm, world
    Eigen::Vector3d look_at = Eigen::Vector3d::Zero();       ///< mm, world
    Eigen::Vector3d up = Eigen::Vector3d::UnitY();           ///< world; need not be unit
    double vertical_fov = 0.5;                               ///< full angle, radians
    int width = 256;                                         ///< pixels
    int height = 128;                                        ///< pixels

    Eigen::Vector3d forward() const { return (look_at - position).normalized(); }
    Eigen::Vector3d right() const { return forward().cross(up).normalized(); }
    Eigen::Vector3d image_up() const { return right().cross(forward()); }
    /// Columns: the field frame's x (right), y (image up) and z (toward the camera) in world
    /// coordinates. world = field_frame() * field.
    Eigen::Matrix3d field_frame() const;
    /// Unit world direction of the ray from `position` through image point (px, py).
    Eigen::Vector3d ray_direction(double px, double py) const;
    /// Image point (px, py) of a world point in front of the camera: the inverse of
    /// ray_direction(). Points behind the camera project to NaN.
    Eigen::Vector2d project(const Eigen::Vector3d& world) const;
    /// Bounding box (x, y, width, height in continuous image coordinates) of a sphere's
    /// image: the projection of its silhouette circle, an ellipse off the optical axis.
    Eigen::Vector4d sphere_box(const Eigen::Vector3d& centre, double radius) const;
};

/// A solid checkerboard in world millimetres: cube (i, j, k) of edge `square` has colour
/// `first` when i + j + k is even. Works on every shape, curved ones included. It is looked
/// up a quarter square below the surface (against the normal), so a surface lying in a
/// cube face, such as a table at z = 0, shows clean squares rather than rounding noise.
struct CheckerTexture {
    double square = 10.0;  ///< mm
    Rgb first = Rgb::Constant(0.8);
    Rgb second = Rgb::Constant(0.2);
};

/// An image mapped over a card or plane (uv of relight/mesh.hpp), bilinear, clamped at the
/// border. Linear values, as core/image_io decodes them.
struct ImageTexture {
    std::shared_ptr<const Image> image;
    std::filesystem::path file;
};

/// Diffuse reflectance (albedo, 0..1 per channel): constant, checker or image.
using Albedo = std::variant<Rgb, CheckerTexture, ImageTexture>;

struct DiffuseMaterial {
    Albedo albedo = Rgb::Constant(0.8);
};
/// The glossy model of relight/brdf.hpp.
struct GlossyMaterial {
    Albedo albedo = Rgb::Constant(0.5);
    Rgb specular = Rgb::Constant(0.04);  ///< Fresnel reflectance at normal incidence
    double roughness = 0.2;              ///< GGX alpha, (0, 1]
};
/// The Phong plus Fresnel model of relight/brdf.hpp: the thesis's synthetic snooker ball.
struct PhongMaterial {
    Albedo albedo = Rgb::Constant(0.02);
    double exponent = 50.0;  ///< Phong exponent, > 0
    double ior = 1.5;        ///< index of refraction of the dielectric, > 1
};
/// A perfect mirror, reflectance per channel.
struct MirrorMaterial {
    Rgb reflectance = Rgb::Constant(0.9);
};
/// A clear or coloured dielectric (glass, liquid): Fresnel reflection and Snell refraction
/// at its surface, Beer-Lambert absorption inside.
struct GlassMaterial {
    double ior = 1.5;                   ///< index of refraction (outside: air, 1)
    Rgb absorption = Rgb::Zero();       ///< absorption coefficient per mm
};
using Material = std::variant<DiffuseMaterial, GlossyMaterial, PhongMaterial, MirrorMaterial, GlassMaterial>;

/// The albedo of a diffuse, glossy or Phong material; nullptr for mirror and glass.
const Albedo* albedo_of(const Material& material);

/// f_r of an opaque, non-mirror material (diffuse, glossy, Phong) with the albedo looked up
/// at the point: unit vectors n (shading normal), v (toward the viewer), l (toward the light).
Rgb surface_brdf(const Material& material, const Eigen::Vector3d& n, const Eigen::Vector3d& v,
                 const Eigen::Vector3d& l, const Rgb& albedo);

struct SphereShape {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< mm
    double radius = 1.0;                               ///< mm
};
/// A closed cylinder: side and two flat caps, from `base` along the unit `axis`.
struct CylinderShape {
    Eigen::Vector3d base = Eigen::Vector3d::Zero();  ///< centre of the bottom cap, mm
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< unit
    double radius = 1.0;                              ///< mm
    double height = 1.0;                              ///< mm
};
using Shape = std::variant<SphereShape, CylinderShape, MeshShape>;

struct SceneObject {
    std::string name;
    Shape shape;
    std::size_t material = 0;  ///< index into Scene::materials
};

struct Scene {
    std::string name;                      ///< the file's stem
    std::vector<Camera> cameras;           ///< views; cameras[0] defines the field frame
    int samples_per_pixel = 4;             ///< camera rays per pixel (1: the pixel centre)
    std::vector<std::string> material_names;
    std::vector<Material> materials;
    std::vector<SceneObject> objects;
    LightKernel kernel = LightKernel::narrow();
    int shadow_samples = 1;                ///< kernel samples per camera sample
    Rgb background = Rgb::Zero();          ///< radiance of escaping rays, for every light
    std::uint64_t seed = 1;
    int max_depth = 8;                     ///< mirror and glass interactions per camera path
};

/// Reads a scene file. Throws InputError naming file:line:key for any malformed or unknown
/// key, bad material, missing mesh or texture file; IoError when the file cannot be read.
Scene load_scene(const std::filesystem::path& file);
/// The same from text; `name` stands for the file in messages, relative paths (meshes,
/// textures) are taken from `base_dir`.
Scene parse_scene(std::string_view text, const std::string& name,
                  const std::filesystem::path& base_dir);

/// Albedo at world point p with outward geometric normal n and texture coordinates uv.
Rgb albedo_at(const Albedo& albedo, const Eigen::Vector3d& p, const Eigen::Vector3d& n,
              const Eigen::Vector2d& uv);

/// Shadow samples for a kernel when the scene does not say: one for a directional or
/// narrow (<= 3 degrees) kernel, four otherwise.
int default_shadow_samples(const LightKernel& kernel);

}  // namespace rfd::relight
