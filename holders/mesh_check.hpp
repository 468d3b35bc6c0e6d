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
#include <string>
#include <vector>

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

}  // namespace rfd::holders
