#include "holders/mesh_check.hpp"

#include <algorithm>
#include <fstream>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/IO/STL.h>
#include <CGAL/Surface_mesh.h>

#include "core/error.hpp"

namespace rfd::holders {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;

}  // namespace

std::vector<std::string> MeshCheck::problems() const {
    std::vector<std::string> out;
    if (!manifold) out.push_back("the faces are not consistently oriented, or an edge joins more than two faces");
    if (!closed) out.push_back("the mesh is not closed (some edges border one face only)");
    if (self_intersecting) out.push_back("the mesh intersects itself");
    if (closed && !self_intersecting && !bounds_volume) out.push_back("the mesh does not bound a volume");
    if (closed && !outward) out.push_back("the mesh is oriented inside out");
    if (components != 1) out.push_back("the mesh has " + std::to_string(components) + " separate pieces, expected one");
    return out;
}

MeshCheck check_stl(const std::filesystem::path& stl) {
    std::vector<Point> points;
    std::vector<std::array<std::size_t, 3>> triangles;
    std::ifstream in(stl, std::ios::binary);
    if (!in || !CGAL::IO::read_STL(in, points, triangles, CGAL::parameters::verbose(false)) || triangles.empty())
        throw IoError(stl.string() + ": cannot read a triangle mesh (STL) from it");
    // STL repeats each vertex per triangle: merge them, then build a surface mesh.
    PMP::repair_polygon_soup(points, triangles);
    MeshCheck check;
    // Faces that disagree on orientation, or edges shared by more than two faces, make no
    // surface mesh as they stand: orient the soup (duplicating non-manifold vertices) and say so.
    check.manifold = PMP::is_polygon_soup_a_polygon_mesh(triangles);
    if (!check.manifold) PMP::orient_polygon_soup(points, triangles);
    Mesh mesh;
    PMP::polygon_soup_to_polygon_mesh(points, triangles, mesh);

    check.vertices = mesh.number_of_vertices();
    check.faces = mesh.number_of_faces();
    check.closed = CGAL::is_closed(mesh);
    check.self_intersecting = PMP::does_self_intersect(mesh);
    if (check.closed && !check.self_intersecting) {
        check.bounds_volume = PMP::does_bound_a_volume(mesh);
        check.outward = PMP::is_outward_oriented(mesh);
        check.volume_mm3 = std::abs(PMP::volume(mesh));
    }
    auto component = mesh.add_property_map<Mesh::Face_index, std::size_t>("f:component", 0).first;
    check.components = PMP::connected_components(mesh, component);
    const CGAL::Bbox_3 box = PMP::bbox(mesh);
    check.min_mm = {box.xmin(), box.ymin(), box.zmin()};
    check.max_mm = {box.xmax(), box.ymax(), box.zmax()};
    return check;
}

}  // namespace rfd::holders
