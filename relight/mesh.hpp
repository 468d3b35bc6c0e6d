#pragma once
// Triangle meshes of the virtual light stage: read from OBJ or PLY (through CGAL's polygon
// soup readers), or built for boxes and rectangles.
//
// Positions are millimetres in the scene's world frame once placed (the scene applies the
// file's scale, rotation and translation). Triangles wind counter-clockwise seen from
// outside, so the geometric normal (b - a) x (c - a) points out of a closed solid; glass
// relies on it to tell entering from leaving. `normals`, when present, are per-vertex
// shading normals (smooth surfaces); when empty the faces shade flat. `uvs`, when present,
// are per-vertex texture coordinates (u right, v down the image, both in [0, 1]).
//
// Example: MeshShape mesh = read_mesh("scenes/figure.obj"); compute_vertex_normals(mesh);

#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rfd::relight {

struct MeshShape {
    std::vector<Eigen::Vector3f> positions;              ///< mm
    std::vector<Eigen::Vector3f> normals;                ///< unit, per vertex, or empty
    std::vector<Eigen::Vector2f> uvs;                    ///< per vertex, or empty
    std::vector<std::array<std::uint32_t, 3>> triangles;  ///< vertex indices

    friend bool operator==(const MeshShape&, const MeshShape&) = default;
};

/// Reads an OBJ or PLY file (by extension) as a polygon soup and fans polygons into
/// triangles. Throws IoError when it cannot be read, InputError when it holds no triangle,
/// an index out of range or a non-finite coordinate; messages name the file.
MeshShape read_mesh(const std::filesystem::path& path);

/// Angle-weighted vertex normals (Thuermer and Wuethrich 1998): smooth shading that does not
/// depend on how a face was split into triangles.
void compute_vertex_normals(MeshShape& mesh);

/// Applies p -> rotation * (scale * p) + translation to positions, and the rotation to normals.
void transform_mesh(MeshShape& mesh, double scale, const Eigen::Matrix3d& rotation,
                    const Eigen::Vector3d& translation);

/// A box of the given full size (mm) centred at the origin, axis-aligned, 12 triangles,
/// flat faces (no vertex normals).
MeshShape box_mesh(const Eigen::Vector3d& size);

/// A rectangle centred at `centre` spanning +-half_u along `u_axis` and +-half_v along
/// `v_axis` (unit, orthogonal), facing u_axis x v_axis; uv (0, 0) at the corner
/// centre - half_u u + half_v v (top left, looking at its face with v up).
MeshShape rectangle_mesh(const Eigen::Vector3d& centre, const Eigen::Vector3d& u_axis,
                         const Eigen::Vector3d& v_axis, double half_u, double half_v);

}  // namespace rfd::relight
