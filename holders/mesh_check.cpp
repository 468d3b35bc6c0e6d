#include "holders/mesh_check.hpp"

#include <algorithm>
#include <fstream>
#include <numeric>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/IO/STL.h>
#include <CGAL/Surface_mesh.h>

#include "core/error.hpp"

#include <Eigen/Geometry>

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

namespace {

// Triangles as vectors, not arrays: then repair_polygon_soup also drops triangles whose
// corners coincide once the STL's repeated vertices are merged.
using Soup = std::vector<std::vector<std::size_t>>;

// OpenSCAD writes the same triangles in an order that changes from run to run. Sorted (the
// points by coordinates, each triangle turned to start at its lowest point, which keeps its
// orientation, then the triangles), the soup depends only on the surface, and so do the
// mesh made from it and the STL written back: a holder made twice is the same file.
void put_in_canonical_order(std::vector<Point>& points, Soup& triangles) {
    std::vector<std::size_t> order(points.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return points[a] < points[b]; });
    std::vector<std::size_t> rank(points.size());
    std::vector<Point> sorted(points.size());
    for (std::size_t r = 0; r < order.size(); ++r) {
        rank[order[r]] = r;
        sorted[r] = points[order[r]];
    }
    points = std::move(sorted);
    for (std::vector<std::size_t>& triangle : triangles) {
        for (std::size_t& corner : triangle) corner = rank[corner];
        std::rotate(triangle.begin(), std::min_element(triangle.begin(), triangle.end()), triangle.end());
    }
    std::sort(triangles.begin(), triangles.end());
}

void read_soup(const std::filesystem::path& stl, std::vector<Point>& points, Soup& triangles) {
    std::ifstream in(stl, std::ios::binary);
    if (!in || !CGAL::IO::read_STL(in, points, triangles, CGAL::parameters::verbose(false)) || triangles.empty())
        throw IoError(stl.string() + ": cannot read a triangle mesh (STL) from it");
    // STL repeats each vertex per triangle: merge them.
    PMP::repair_polygon_soup(points, triangles);
    put_in_canonical_order(points, triangles);
}

}  // namespace

std::size_t remove_slivers(const std::filesystem::path& stl, double sliver_mm) {
    std::vector<Point> points;
    Soup triangles;
    read_soup(stl, points, triangles);
    // A mesh that is not one surface as it stands is left as it is, for check_stl to report:
    // mending it here would hide it.
    if (!PMP::is_polygon_soup_a_polygon_mesh(triangles)) return 0;
    Mesh mesh;
    PMP::polygon_soup_to_polygon_mesh(points, triangles, mesh);
    const std::size_t before = mesh.number_of_faces();
    PMP::remove_degenerate_faces(mesh);
    // A needle: longest edge over 100 times its shortest. Caps (one angle near 180 degrees)
    // are left alone: they are mended by flipping an edge, which moves the surface where the
    // two triangles do not lie in one plane (it took 0.5 % off the coupon's volume).
    const double no_caps = -1.0;  // the cosine no angle falls below
    PMP::experimental::remove_almost_degenerate_faces(mesh, no_caps, 100.0, sliver_mm);
    mesh.collect_garbage();
    const std::size_t removed = before - mesh.number_of_faces();
    std::ofstream out(stl, std::ios::binary | std::ios::trunc);
    CGAL::IO::set_binary_mode(out);
    if (!out || !CGAL::IO::write_STL(out, mesh) || !out.flush())
        throw IoError(stl.string() + ": cannot write the STL");
    return removed;
}

MeshCheck check_stl(const std::filesystem::path& stl) {
    std::vector<Point> points;
    Soup triangles;
    read_soup(stl, points, triangles);
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

namespace {

using Triangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using AabbTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Point to_point(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

}  // namespace

struct MeshProbe::Tree {
    std::vector<Triangle> triangles;
    AabbTree tree;
};

MeshProbe::MeshProbe(const std::filesystem::path& stl) : tree_(std::make_unique<Tree>()) {
    std::vector<Point> points;
    Soup faces;
    read_soup(stl, points, faces);
    for (const auto& f : faces) {
        Triangle t(points[f[0]], points[f[1]], points[f[2]]);
        if (!t.is_degenerate()) tree_->triangles.push_back(t);
    }
    tree_->tree.insert(tree_->triangles.cbegin(), tree_->triangles.cend());
    tree_->tree.build();
    tree_->tree.accelerate_distance_queries();
    // Build the distance search structure now, not lazily on the first query: queries
    // then only read the tree and may run in parallel.
    if (!tree_->triangles.empty()) (void)tree_->tree.squared_distance(tree_->triangles.front().vertex(0));
}

MeshProbe::~MeshProbe() = default;
MeshProbe::MeshProbe(MeshProbe&&) noexcept = default;
MeshProbe& MeshProbe::operator=(MeshProbe&&) noexcept = default;

std::optional<double> MeshProbe::first_hit_z(double x, double y, double z_from, int direction) const {
    const double far = 1e5 * direction;
    const Kernel::Segment_3 segment(Point(x, y, z_from), Point(x, y, z_from + far));
    std::vector<Primitive::Id> hit;
    tree_->tree.all_intersected_primitives(segment, std::back_inserter(hit));
    std::optional<double> best;
    for (const auto& id : hit) {
        // Where the vertical line meets the triangle's plane (a, b, c: its corners).
        const Triangle& t = *id;
        const Eigen::Vector3d a(t[0].x(), t[0].y(), t[0].z()), b(t[1].x(), t[1].y(), t[1].z()),
            c(t[2].x(), t[2].y(), t[2].z());
        const Eigen::Vector3d n = (b - a).cross(c - a);
        double z;
        if (std::abs(n.z()) > 1e-12 * n.norm()) {
            z = a.z() - (n.x() * (x - a.x()) + n.y() * (y - a.y())) / n.z();
        } else {
            z = direction > 0 ? std::min({a.z(), b.z(), c.z()}) : std::max({a.z(), b.z(), c.z()});  // edge-on
        }
        if (!best || (direction > 0 ? z < *best : z > *best)) best = z;
    }
    return best;
}

bool MeshProbe::hits(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
    return tree_->tree.do_intersect(Kernel::Segment_3(to_point(a), to_point(b)));
}

double MeshProbe::distance(const Eigen::Vector3d& p) const {
    return std::sqrt(CGAL::to_double(tree_->tree.squared_distance(to_point(p))));
}

}  // namespace rfd::holders
