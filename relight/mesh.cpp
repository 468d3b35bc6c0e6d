#include "relight/mesh.hpp"

#include <cmath>
#include <string>

#include <CGAL/IO/OBJ.h>
#include <CGAL/IO/PLY.h>
#include <CGAL/Simple_cartesian.h>

#include "core/error.hpp"

namespace rfd::relight {
namespace {

using CgalPoint = CGAL::Simple_cartesian<double>::Point_3;

std::string lower_extension(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

}  // namespace

MeshShape read_mesh(const std::filesystem::path& path) {
    const SourceLocation where{path.string()};
    const std::string ext = lower_extension(path);
    if (ext != ".obj" && ext != ".ply")
        throw InputError(where, "mesh files must be .obj or .ply, got '" + ext + "'");
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw IoError(where, "cannot open mesh file");
    std::vector<CgalPoint> points;
    std::vector<std::vector<std::size_t>> polygons;
    const bool ok = ext == ".obj" ? CGAL::IO::read_OBJ(path.string(), points, polygons)
                                  : CGAL::IO::read_PLY(path.string(), points, polygons);
    if (!ok) throw InputError(where, "cannot parse the mesh (CGAL's " + ext.substr(1) + " reader failed)");
    MeshShape mesh;
    mesh.positions.reserve(points.size());
    for (const CgalPoint& p : points) {
        if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z()))
            throw InputError(where, "vertex " + std::to_string(mesh.positions.size()) +
                                        " has a non-finite coordinate");
        mesh.positions.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                    static_cast<float>(p.z()));
    }
    for (std::size_t f = 0; f < polygons.size(); ++f) {
        const auto& polygon = polygons[f];
        for (const std::size_t index : polygon)
            if (index >= points.size())
                throw InputError(where, "face " + std::to_string(f) + " uses vertex " +
                                            std::to_string(index) + " of " +
                                            std::to_string(points.size()));
        // Fan triangulation: exact for the convex faces mesh writers produce.
        for (std::size_t k = 2; k < polygon.size(); ++k)
            mesh.triangles.push_back({static_cast<std::uint32_t>(polygon[0]),
                                      static_cast<std::uint32_t>(polygon[k - 1]),
                                      static_cast<std::uint32_t>(polygon[k])});
    }
    if (mesh.triangles.empty()) throw InputError(where, "the mesh has no faces");
    return mesh;
}

void compute_vertex_normals(MeshShape& mesh) {
    std::vector<Eigen::Vector3d> sums(mesh.positions.size(), Eigen::Vector3d::Zero());
    for (const auto& t : mesh.triangles) {
        const Eigen::Vector3d p[3] = {mesh.positions[t[0]].cast<double>(),
                                      mesh.positions[t[1]].cast<double>(),
                                      mesh.positions[t[2]].cast<double>()};
        const Eigen::Vector3d normal = (p[1] - p[0]).cross(p[2] - p[0]);
        if (normal.norm() == 0.0) continue;  // degenerate triangles carry no direction
        const Eigen::Vector3d unit = normal.normalized();
        for (int k = 0; k < 3; ++k) {
            const Eigen::Vector3d e1 = (p[(k + 1) % 3] - p[k]).normalized();
            const Eigen::Vector3d e2 = (p[(k + 2) % 3] - p[k]).normalized();
            const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
            sums[t[static_cast<std::size_t>(k)]] += angle * unit;
        }
    }
    mesh.normals.resize(mesh.positions.size());
    for (std::size_t i = 0; i < sums.size(); ++i) {
        const double length = sums[i].norm();
        mesh.normals[i] = length > 0.0 ? Eigen::Vector3f((sums[i] / length).cast<float>())
                                       : Eigen::Vector3f(0.0f, 0.0f, 1.0f);
    }
}

void transform_mesh(MeshShape& mesh, double scale, const Eigen::Matrix3d& rotation,
                    const Eigen::Vector3d& translation) {
    for (auto& p : mesh.positions)
        p = (rotation * (scale * p.cast<double>()) + translation).cast<float>();
    for (auto& n : mesh.normals) n = (rotation * n.cast<double>()).normalized().cast<float>();
}

MeshShape box_mesh(const Eigen::Vector3d& size) {
    MeshShape mesh;
    const Eigen::Vector3d half = 0.5 * size;
    // Each face: its outward axis, and two tangents with t1 x t2 = outward.
    for (int axis = 0; axis < 3; ++axis) {
        for (const double sign : {-1.0, 1.0}) {
            Eigen::Vector3d normal = Eigen::Vector3d::Zero();
            normal[axis] = sign;
            Eigen::Vector3d t1 = Eigen::Vector3d::Zero();
            t1[(axis + 1) % 3] = 1.0;
            const Eigen::Vector3d t2 = normal.cross(t1);
            const Eigen::Vector3d centre = normal.cwiseProduct(half);
            const double h1 = half[(axis + 1) % 3];
            const double h2 = t2.cwiseAbs().dot(half);
            const auto base = static_cast<std::uint32_t>(mesh.positions.size());
            for (const auto& [a, b] : {std::pair{-1.0, -1.0}, {1.0, -1.0}, {1.0, 1.0}, {-1.0, 1.0}})
                mesh.positions.push_back((centre + a * h1 * t1 + b * h2 * t2).cast<float>());
            mesh.triangles.push_back({base, base + 1, base + 2});
            mesh.triangles.push_back({base, base + 2, base + 3});
        }
    }
    return mesh;
}

MeshShape rectangle_mesh(const Eigen::Vector3d& centre, const Eigen::Vector3d& u_axis,
                         const Eigen::Vector3d& v_axis, double half_u, double half_v) {
    MeshShape mesh;
    // Corners: top left, top right, bottom right, bottom left (v up).
    const Eigen::Vector3d corners[4] = {
        centre - half_u * u_axis + half_v * v_axis, centre + half_u * u_axis + half_v * v_axis,
        centre + half_u * u_axis - half_v * v_axis, centre - half_u * u_axis - half_v * v_axis};
    const Eigen::Vector2f uvs[4] = {{0.0f, 0.0f}, {1.0f, 0.0f}, {1.0f, 1.0f}, {0.0f, 1.0f}};
    for (int k = 0; k < 4; ++k) {
        mesh.positions.push_back(corners[k].cast<float>());
        mesh.uvs.push_back(uvs[k]);
    }
    // Counter-clockwise seen from the face (u x v): bottom left, bottom right, top right...
    mesh.triangles = {{3, 2, 1}, {3, 1, 0}};
    return mesh;
}

}  // namespace rfd::relight
