#pragma once
// Checks that a printed part's mesh (an STL from openscad) is a solid a slicer will take:
// closed (every edge has two faces), bounding a volume, outward oriented, free of
// self-intersections, in exactly one connected piece; and measures its volume and
// bounding box to compare with the design. CGAL's Polygon Mesh Processing does the work.
//
// Units: millimetres (the STL's), volumes in mm^3.
//
// Example: MeshCheck c = check_stl("holder.stl"); if (!c.problems().empty()) ...

#include <array>
#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace rfd::holders {

struct MeshCheck {
    std::size_t vertices = 0, faces = 0;
    bool manifold = false;         ///< consistently oriented, two faces per edge at most
    bool closed = false;
    bool bounds_volume = false;    ///< closed, oriented consistently, no self-intersection
    bool outward = false;          ///< normals point out of the solid
    bool self_intersecting = false;
    std::size_t components = 0;    ///< connected pieces
    double volume_mm3 = 0.0;       ///< enclosed volume (0 unless closed)
    std::array<double, 3> min_mm{}, max_mm{};

    /// What a slicer would object to, one sentence each; empty for a good solid.
    std::vector<std::string> problems() const;
};

/// Reads an STL (ASCII or binary) and checks it. IoError when it cannot be read or holds
/// no triangles.
MeshCheck check_stl(const std::filesystem::path& stl);

/// Removes the slivers of OpenSCAD's tessellation from an STL and rewrites it as binary STL
/// (float coordinates). OpenSCAD triangulates each flat face of its exact result and writes
/// six significant digits: on a part over 100 mm wide, the long thin triangles fanned over
/// a face with holes can fold over their neighbours by a micrometre, and triangles on a
/// straight edge have no area. Zero-area triangles go, and needles whose shortest edge is
/// below `sliver_mm` are collapsed (moving a vertex by less than that). Returns how many
/// triangles were removed. A mesh that is not one consistently oriented surface is left
/// untouched (0), for check_stl to report. IoError when the file cannot be read or written.
std::size_t remove_slivers(const std::filesystem::path& stl, double sliver_mm = 0.01);

}  // namespace rfd::holders

namespace rfd::holders {

/// Geometric queries on a printed part's mesh, for the seat and beam-clearance checks:
/// an AABB tree (CGAL) over the STL's triangles. Millimetres, the STL's frame.
class MeshProbe {
public:
    /// Reads the STL; IoError when it cannot be read or holds no triangles.
    explicit MeshProbe(const std::filesystem::path& stl);
    ~MeshProbe();
    MeshProbe(MeshProbe&&) noexcept;
    MeshProbe& operator=(MeshProbe&&) noexcept;

    /// z where the line x, y (parallel to the z axis), followed from z_from toward
    /// z_from + direction * infinity (direction +1 or -1), first meets the mesh.
    std::optional<double> first_hit_z(double x, double y, double z_from, int direction) const;
    /// Whether the segment from a to b touches the mesh.
    bool hits(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const;
    /// Distance from p to the nearest point of the mesh.
    double distance(const Eigen::Vector3d& p) const;

private:
    struct Tree;
    std::unique_ptr<Tree> tree_;
};

}  // namespace rfd::holders
