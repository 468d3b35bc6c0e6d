#include "tests/support/hull_triangles.hpp"

#include <map>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

namespace rfd::testing {

std::vector<relight::Triangle> hull_triangles(const std::vector<Eigen::Vector3d>& directions) {
    using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
    using Point = Kernel::Point_3;
    std::vector<Point> points;
    std::map<Point, std::size_t> index;
    for (std::size_t i = 0; i < directions.size(); ++i) {
        points.emplace_back(directions[i].x(), directions[i].y(), directions[i].z());
        index[points.back()] = i;
    }
    const Point guardian(0, 0, -1);
    points.push_back(guardian);
    CGAL::Surface_mesh<Point> hull;
    CGAL::convex_hull_3(points.begin(), points.end(), hull);
    std::vector<relight::Triangle> triangles;
    for (const auto face : hull.faces()) {
        relight::Triangle t{};
        std::size_t corner = 0;
        bool has_guardian = false;
        for (const auto v : CGAL::vertices_around_face(hull.halfedge(face), hull)) {
            if (hull.point(v) == guardian) has_guardian = true;
            else t[corner] = index.at(hull.point(v));
            ++corner;
        }
        if (!has_guardian) triangles.push_back(t);
    }
    return triangles;
}

}  // namespace rfd::testing
