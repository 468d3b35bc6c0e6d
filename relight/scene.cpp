#include "relight/scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

#include <Eigen/Geometry>

#include "core/config.hpp"
#include "core/error.hpp"
#include "core/image_io.hpp"
#include "core/units.hpp"

namespace rfd::relight {
namespace {

constexpr double kHuge = 1e9;  // mm: bounds coordinates to something a float can hold

// A length (or scale) > 0, bounded as coordinates are: Embree aborts on a ray through a
// 1e30 mm sphere.
double size(ConfigTable& table, const std::string& key) {
    table.number(key, -kHuge, kHuge);  // bounded, with the range in the message
    return table.positive(key);
}

// Two sizes > 0 (a card's width and height), bounded as coordinates are.
std::array<double, 2> size_pair(ConfigTable& table, const std::string& key) {
    table.numbers(key, 2, -kHuge, kHuge);  // bounded, with the range in the message
    return table.positive_pair(key);
}

Eigen::Vector3d vector3(ConfigTable& table, const std::string& key, double min = -kHuge,
                        double max = kHuge) {
    const auto v = table.numbers(key, 3, min, max);
    return {v[0], v[1], v[2]};
}

Eigen::Vector3d optional_vector3(ConfigTable& table, const std::string& key,
                                 const Eigen::Vector3d& fallback) {
    return table.has(key) ? vector3(table, key) : fallback;
}

Eigen::Vector3d direction(ConfigTable& table, const std::string& key,
                          const Eigen::Vector3d& fallback) {
    if (!table.has(key)) return fallback;
    const Eigen::Vector3d v = vector3(table, key);
    if (!(v.norm() > 1e-12)) table.fail(key, "expected a non-zero direction");
    return v.normalized();
}

Rgb colour(ConfigTable& table, const std::string& key, double max = 1.0) {
    const auto v = table.numbers(key, 3, 0.0, max);
    return {v[0], v[1], v[2]};
}

Rgb optional_colour(ConfigTable& table, const std::string& key, const Rgb& fallback,
                    double max = 1.0) {
    return table.has(key) ? colour(table, key, max) : fallback;
}

// rotate_deg = [x, y, z]: rotations about the world axes, x first.
Eigen::Matrix3d rotation(ConfigTable& table, const std::string& key) {
    if (!table.has(key)) return Eigen::Matrix3d::Identity();
    const Eigen::Vector3d r = vector3(table, key, -360.0, 360.0);
    return (Eigen::AngleAxisd(degrees_to_radians(r.z()), Eigen::Vector3d::UnitZ()) *
            Eigen::AngleAxisd(degrees_to_radians(r.y()), Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(degrees_to_radians(r.x()), Eigen::Vector3d::UnitX()))
        .toRotationMatrix();
}

std::filesystem::path resolve(const std::filesystem::path& base_dir, const std::string& file) {
    const std::filesystem::path path(file);
    return path.is_absolute() ? path : base_dir / path;
}

Albedo read_albedo(ConfigTable& table, const std::filesystem::path& base_dir,
                   const Rgb& fallback) {
    const bool has_texture = table.has("texture");
    const bool has_checker = table.has("checker_mm");
    if (has_texture && (has_checker || table.has("albedo")))
        table.fail("texture", "give either 'texture' or 'albedo' (with 'checker_mm'), not both");
    if (has_texture) {
        const std::string file = table.string("texture");
        const auto path = resolve(base_dir, file);
        Image image;
        try {
            image = read_image(path);
        } catch (const Error& error) {
            rethrow_at(error, table.location("texture"), std::string("cannot read texture: ") + error.what());
        }
        for (const float v : image.samples())
            if (v > 1.0f)
                table.fail("texture", "texture '" + file + "' holds values above 1; an albedo "
                                      "texture must stay within [0, 1]");
        return ImageTexture{std::make_shared<const Image>(std::move(image)), path};
    }
    const Rgb albedo = optional_colour(table, "albedo", fallback);
    if (!has_checker) {
        if (table.has("checker_albedo"))
            table.fail("checker_albedo", "needs 'checker_mm' (the square size)");
        return albedo;
    }
    CheckerTexture checker;
    checker.square = size(table, "checker_mm");
    checker.first = albedo;
    checker.second = optional_colour(table, "checker_albedo", Rgb::Constant(0.1));
    return checker;
}

Material read_material(ConfigTable& table, const std::filesystem::path& base_dir) {
    const std::string type = table.choice("type", {"diffuse", "glossy", "phong", "mirror", "glass"});
    if (type == "diffuse") return DiffuseMaterial{read_albedo(table, base_dir, Rgb::Constant(0.8))};
    if (type == "glossy") {
        GlossyMaterial glossy;
        glossy.albedo = read_albedo(table, base_dir, Rgb::Constant(0.5));
        glossy.specular = optional_colour(table, "specular", glossy.specular);
        glossy.roughness = table.number("roughness", 1e-3, 1.0);
        return glossy;
    }
    if (type == "phong") {
        PhongMaterial phong;
        phong.albedo = read_albedo(table, base_dir, Rgb::Constant(0.02));
        phong.exponent = table.number("exponent", 1e-3, 1e6);
        if (table.has("ior")) phong.ior = table.number("ior", 1.0 + 1e-6, 4.0);
        return phong;
    }
    if (type == "mirror") return MirrorMaterial{optional_colour(table, "reflectance", Rgb::Constant(0.9))};
    GlassMaterial glass;
    glass.ior = table.number("ior", 1.0, 4.0);
    glass.absorption = optional_colour(table, "absorption_per_mm", Rgb::Zero(), 1e6);
    return glass;
}

Camera read_camera(ConfigTable& table, const Camera* first) {
    Camera camera;
    if (first) camera = *first;
    camera.position = vector3(table, "position_mm");
    if (first) {
        camera.look_at = optional_vector3(table, "look_at_mm", first->look_at);
        camera.up = direction(table, "up", first->up);
        if (table.has("fov_deg")) camera.vertical_fov = degrees_to_radians(table.number("fov_deg", 0.01, 170.0));
    } else {
        camera.look_at = vector3(table, "look_at_mm");
        camera.up = direction(table, "up", Eigen::Vector3d::UnitY());
        camera.vertical_fov = degrees_to_radians(table.number("fov_deg", 0.01, 170.0));
        const auto resolution = table.integer_pair("resolution", 1, 16384);
        camera.width = static_cast<int>(resolution[0]);
        camera.height = static_cast<int>(resolution[1]);
    }
    const Eigen::Vector3d view = camera.look_at - camera.position;
    if (!(view.norm() > 1e-9)) table.fail("look_at_mm", "the camera looks at its own position");
    if (view.normalized().cross(camera.up).norm() < 1e-6)
        table.fail("up", "'up' is parallel to the viewing direction");
    return camera;
}

LightKernel read_kernel(ConfigTable& table) {
    const std::string profile = table.choice("profile", {"directional", "constant", "smooth", "gaussian"});
    if (profile == "directional") return LightKernel::directional();
    if (profile == "gaussian") return LightKernel::gaussian(degrees_to_radians(table.number("sigma_deg", 1e-3, 30.0)));
    const double radius = degrees_to_radians(table.number("radius_deg", 1e-3, 90.0));
    if (profile == "smooth") return LightKernel::smooth(radius);
    return {KernelProfile::Constant, radius, 0.0};
}

SceneObject read_object(ConfigTable& table, const std::map<std::string, std::size_t>& material_index,
                        const std::vector<Material>& materials, const std::filesystem::path& base_dir,
                        std::size_t index) {
    SceneObject object;
    const std::string type =
        table.choice("type", {"sphere", "cylinder", "box", "card", "plane", "mesh"});
    object.name = table.optional_string("name").value_or(type + "_" + std::to_string(index));
    const std::string material = table.string("material");
    const auto found = material_index.find(material);
    if (found == material_index.end()) {
        std::string known;
        for (const auto& [name, i] : material_index) known += (known.empty() ? "" : ", ") + name;
        table.fail("material", "no material named '" + material + "' (defined: " +
                                   (known.empty() ? "none" : known) + ")");
    }
    object.material = found->second;
    const Material& m = materials[object.material];

    if (type == "sphere") {
        object.shape = SphereShape{vector3(table, "center_mm"), size(table, "radius_mm")};
    } else if (type == "cylinder") {
        CylinderShape cylinder;
        cylinder.base = vector3(table, "base_mm");
        cylinder.axis = direction(table, "axis", Eigen::Vector3d::UnitZ());
        cylinder.radius = size(table, "radius_mm");
        cylinder.height = size(table, "height_mm");
        object.shape = cylinder;
    } else if (type == "box") {
        const Eigen::Vector3d centre = vector3(table, "center_mm");
        const Eigen::Vector3d size = vector3(table, "size_mm", 0.0, kHuge);
        if (!(size.minCoeff() > 0.0)) table.fail("size_mm", "expected three positive sizes");
        MeshShape mesh = box_mesh(size);
        transform_mesh(mesh, 1.0, rotation(table, "rotate_deg"), centre);
        object.shape = std::move(mesh);
    } else if (type == "card" || type == "plane") {
        const bool card = type == "card";
        const Eigen::Vector3d centre = vector3(table, card ? "center_mm" : "point_mm");
        const Eigen::Vector3d normal = direction(table, "normal", Eigen::Vector3d::UnitZ());
        // Default "up" of the texture: world +y, or +z for a plane facing along y.
        const Eigen::Vector3d default_up =
            std::abs(normal.y()) > 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitY();
        Eigen::Vector3d up = direction(table, "up", default_up);
        up = (up - up.dot(normal) * normal);
        if (up.norm() < 1e-6) table.fail("up", "'up' is parallel to the normal");
        up.normalize();
        const Eigen::Vector3d u_axis = up.cross(normal);
        std::array<double, 2> size{2000.0, 2000.0};
        if (card || table.has("size_mm")) size = size_pair(table, "size_mm");
        object.shape = rectangle_mesh(centre, u_axis, up, 0.5 * size[0], 0.5 * size[1]);
    } else {
        const std::string file = table.string("file");
        MeshShape mesh;
        try {
            mesh = read_mesh(resolve(base_dir, file));
        } catch (const Error& error) {
            rethrow_at(error, table.location("file"), std::string("mesh '") + file + "': " + error.what());
        }
        const double scale = table.has("scale") ? size(table, "scale") : 1.0;
        const bool smooth = table.optional_boolean("smooth").value_or(true);
        if (smooth) compute_vertex_normals(mesh);
        transform_mesh(mesh, scale, rotation(table, "rotate_deg"),
                       optional_vector3(table, "translate_mm", Eigen::Vector3d::Zero()));
        object.shape = std::move(mesh);
    }

    const bool has_uv = std::holds_alternative<MeshShape>(object.shape) &&
                        !std::get<MeshShape>(object.shape).uvs.empty();
    const Albedo* albedo = albedo_of(m);
    if (albedo && std::holds_alternative<ImageTexture>(*albedo) && !has_uv)
        table.fail("material", "material '" + material +
                                   "' has an image texture, which only cards and planes can carry");
    if (std::holds_alternative<GlassMaterial>(m) && (type == "card" || type == "plane"))
        table.fail("material", "glass needs a closed solid (sphere, cylinder, box or closed mesh), "
                               "not a " + type);
    return object;
}

}  // namespace

Eigen::Matrix3d Camera::field_frame() const {
    Eigen::Matrix3d frame;
    frame.col(0) = right();
    frame.col(1) = image_up();
    frame.col(2) = -forward();
    return frame;
}

Eigen::Vector3d Camera::ray_direction(double px, double py) const {
    const double half_height = std::tan(0.5 * vertical_fov);
    const double half_width = half_height * static_cast<double>(width) / static_cast<double>(height);
    const double sx = (2.0 * px / width - 1.0) * half_width;
    const double sy = (1.0 - 2.0 * py / height) * half_height;
    return (forward() + sx * right() + sy * image_up()).normalized();
}

Eigen::Vector2d Camera::project(const Eigen::Vector3d& world) const {
    const Eigen::Vector3d d = world - position;
    const double depth = d.dot(forward());
    if (!(depth > 0.0)) return Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
    const double half_height = std::tan(0.5 * vertical_fov);
    const double half_width = half_height * static_cast<double>(width) / static_cast<double>(height);
    const double sx = d.dot(right()) / depth, sy = d.dot(image_up()) / depth;
    return {0.5 * width * (1.0 + sx / half_width), 0.5 * height * (1.0 - sy / half_height)};
}

Eigen::Vector4d Camera::sphere_box(const Eigen::Vector3d& centre, double radius) const {
    // The silhouette is the circle of tangent points: seen from the camera at distance d, it
    // lies (d^2 - r^2) / d from the camera along the axis, with radius r sqrt(d^2 - r^2) / d.
    const Eigen::Vector3d axis = centre - position;
    const double d = axis.norm();
    if (!(d > radius)) return Eigen::Vector4d::Constant(std::numeric_limits<double>::quiet_NaN());
    const Eigen::Vector3d a = axis / d;
    const Eigen::Vector3d circle_centre = position + a * ((d * d - radius * radius) / d);
    const double circle_radius = radius * std::sqrt(d * d - radius * radius) / d;
    Eigen::Vector3d u, v;
    orthonormal_basis(a, u, v);
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    constexpr int kSteps = 720;  // the ellipse's extremes to within 1e-5 of its size
    for (int i = 0; i < kSteps; ++i) {
        const double t = 2.0 * kPi * i / kSteps;
        const Eigen::Vector2d p = project(circle_centre + circle_radius * (std::cos(t) * u + std::sin(t) * v));
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    return {lo.x(), lo.y(), hi.x() - lo.x(), hi.y() - lo.y()};
}

Rgb albedo_at(const Albedo& albedo, const Eigen::Vector3d& p, const Eigen::Vector3d& n,
              const Eigen::Vector2d& uv) {
    if (const auto* constant = std::get_if<Rgb>(&albedo)) return *constant;
    if (const auto* checker = std::get_if<CheckerTexture>(&albedo)) {
        const Eigen::Vector3d q = p - 0.25 * checker->square * n;
        const auto cell = [&](double x) { return static_cast<long long>(std::floor(x / checker->square)); };
        return ((cell(q.x()) + cell(q.y()) + cell(q.z())) & 1) == 0 ? checker->first : checker->second;
    }
    const Image& image = *std::get<ImageTexture>(albedo).image;
    // Bilinear between texel centres, clamped at the border.
    const double x = std::clamp(uv.x() * image.width() - 0.5, 0.0, image.width() - 1.0);
    const double y = std::clamp(uv.y() * image.height() - 0.5, 0.0, image.height() - 1.0);
    const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
    const int x1 = std::min(x0 + 1, image.width() - 1), y1 = std::min(y0 + 1, image.height() - 1);
    const double fx = x - x0, fy = y - y0;
    Rgb out;
    for (int c = 0; c < 3; ++c) {
        const int channel = std::min(c, image.channels() - 1);  // grey textures
        out[c] = (1 - fy) * ((1 - fx) * image.at(x0, y0, channel) + fx * image.at(x1, y0, channel)) +
                 fy * ((1 - fx) * image.at(x0, y1, channel) + fx * image.at(x1, y1, channel));
    }
    return out;
}

const Albedo* albedo_of(const Material& material) {
    if (const auto* d = std::get_if<DiffuseMaterial>(&material)) return &d->albedo;
    if (const auto* g = std::get_if<GlossyMaterial>(&material)) return &g->albedo;
    if (const auto* p = std::get_if<PhongMaterial>(&material)) return &p->albedo;
    return nullptr;
}

Rgb surface_brdf(const Material& material, const Eigen::Vector3d& n, const Eigen::Vector3d& v,
                 const Eigen::Vector3d& l, const Rgb& albedo) {
    if (const auto* g = std::get_if<GlossyMaterial>(&material))
        return glossy_brdf(n, v, l, albedo, g->specular, g->roughness);
    if (const auto* p = std::get_if<PhongMaterial>(&material))
        return phong_fresnel_brdf(n, v, l, albedo, p->exponent, p->ior);
    return lambert_brdf(n, l, albedo);
}

int default_shadow_samples(const LightKernel& kernel) {
    return kernel.radius <= degrees_to_radians(3.0) ? 1 : 4;
}

static Scene read_scene(ConfigTable& doc, const std::string& name, const std::filesystem::path& base_dir) {
    Scene scene;
    scene.name = std::filesystem::path(name).stem().string();
    if (auto seed = doc.optional_integer("seed", 0, (1LL << 62))) scene.seed = static_cast<std::uint64_t>(*seed);
    scene.background = optional_colour(doc, "background", Rgb::Zero(), kHuge);
    if (auto depth = doc.optional_integer("max_depth", 1, 64)) scene.max_depth = static_cast<int>(*depth);

    auto cameras = doc.table_array("camera");
    for (std::size_t i = 0; i < cameras.size(); ++i) {
        scene.cameras.push_back(read_camera(cameras[i], i == 0 ? nullptr : &scene.cameras.front()));
        if (i == 0)
            if (auto spp = cameras[i].optional_integer("samples_per_pixel", 1, 4096))
                scene.samples_per_pixel = static_cast<int>(*spp);
        cameras[i].finish();
    }

    if (auto kernel = doc.optional_table("kernel")) {
        scene.kernel = read_kernel(*kernel);
        scene.shadow_samples = static_cast<int>(
            kernel->optional_integer("shadow_samples", 1, 1024).value_or(default_shadow_samples(scene.kernel)));
        kernel->finish();
    } else {
        scene.shadow_samples = default_shadow_samples(scene.kernel);
    }

    std::map<std::string, std::size_t> material_index;
    auto materials = doc.table("materials");
    for (const std::string& key : materials.keys()) {
        auto table = materials.table(key);
        material_index[key] = scene.materials.size();
        scene.material_names.push_back(key);
        scene.materials.push_back(read_material(table, base_dir));
        table.finish();
    }
    materials.finish();
    if (scene.materials.empty()) doc.fail("materials", "define at least one material");

    auto objects = doc.table_array("object");
    for (std::size_t i = 0; i < objects.size(); ++i) {
        scene.objects.push_back(read_object(objects[i], material_index, scene.materials, base_dir, i));
        objects[i].finish();
    }
    doc.finish();
    return scene;
}

Scene parse_scene(std::string_view text, const std::string& name,
                  const std::filesystem::path& base_dir) {
    ConfigTable doc = ConfigTable::parse_string(text, name);
    return read_scene(doc, name, base_dir);
}

Scene load_scene(const std::filesystem::path& file) {
    ConfigTable doc = ConfigTable::parse_file(file);
    return read_scene(doc, file.string(), file.parent_path());
}

}  // namespace rfd::relight
